#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz with Debian's clang (-fsanitize=fuzzer,address,undefined) and runs
# each for a bounded time, from a seed corpus of small real meshes (../shared/data/meshes) and hand-made inputs.
#
#   scripts/fuzz.sh [-t SECONDS] [-b BUILD_DIR] [FUZZER...]
#     -t SECONDS    time per fuzzer (default 30; GPUCOL_FUZZ_SECONDS also sets it)
#     -b BUILD_DIR  build folder (default build/fuzz; GPUCOL_FUZZ_BUILD_DIR also sets it)
#     FUZZER        mesh_loader_fuzzer and/or triangle_fuzzer (default: both)
#
# The corpus each run grows is kept in BUILD_DIR/corpus/<fuzzer>; a crashing input is written to
# BUILD_DIR/artifacts/<fuzzer>/ and the script exits non-zero.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${GPUCOL_FUZZ_SECONDS:-30}"
build="${GPUCOL_FUZZ_BUILD_DIR:-$root/build/fuzz}"
while getopts "t:b:h" option; do
  case "$option" in
    t) seconds="$OPTARG" ;;
    b) build="$OPTARG" ;;
    *) sed -n '2,12p' "$0"; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
fuzzers=("$@")
[ ${#fuzzers[@]} -eq 0 ] && fuzzers=(mesh_loader_fuzzer triangle_fuzzer)

"$root/scripts/deps.sh"
cmake -S "$root/tests/fuzz" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${fuzzers[@]}"

# Seeds. The loader's first byte picks the file extension (0 PLY, 1 OBJ, 2 STL, 3 OFF), the rest is the file.
seeds="$build/seeds"
rm -rf "$seeds"
mkdir -p "$seeds/mesh_loader_fuzzer" "$seeds/triangle_fuzzer"
meshes="${GPUCOL_MESH_DIR:-$root/../shared/data/meshes}"
for mesh in bunny-948.ply torus-1152.ply; do
  if [ -f "$meshes/$mesh" ]; then
    { printf '\x00'; cat "$meshes/$mesh"; } > "$seeds/mesh_loader_fuzzer/$mesh"
  else
    echo "fuzz.sh: $meshes/$mesh not found; seeding without it"
  fi
done
tetra_v='v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n'
{ printf '\x01'; printf "$tetra_v"'f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n'; } > "$seeds/mesh_loader_fuzzer/tetra.obj"
{ printf '\x03'; printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n'; } \
  > "$seeds/mesh_loader_fuzzer/tetra.off"
{ printf '\x02'; printf 'solid t\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\n'
  printf 'endloop\nendfacet\nfacet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\n'
  printf 'endloop\nendfacet\nendsolid t\n'; } > "$seeds/mesh_loader_fuzzer/two.stl"
{ printf '\x00'; printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n'
  printf 'property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n'
  printf '0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n'; } > "$seeds/mesh_loader_fuzzer/one.ply"
# One seed per structure each reader knows: binary STL, big-endian PLY with doubles and skipped properties, polygons
# (convex and not) in PLY, OBJ (every corner form, negative indices, groups) and OFF (comments).
python3 - "$seeds/mesh_loader_fuzzer" <<'PY'
import struct, sys
out = sys.argv[1]
tetra = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
stl = b"solid binary header".ljust(80, b" ") + struct.pack("<I", len(faces))
for f in faces:
    stl += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *tetra[i]) for i in f) + b"\0\0"
open(f"{out}/tetra-binary.stl", "wb").write(b"\x02" + stl)
ply = (b"ply\nformat binary_big_endian 1.0\ncomment seed\nelement vertex 4\nproperty double x\nproperty double y\n"
       b"property double z\nproperty uchar red\nelement face 4\nproperty list uchar uint vertex_indices\n"
       b"property float quality\nend_header\n")
for v in tetra:
    ply += struct.pack(">3dB", *v, 7)
for f in faces:
    ply += struct.pack(">B3If", 3, *f, 0.5)
open(f"{out}/tetra-big.ply", "wb").write(b"\x00" + ply)
open(f"{out}/l-shape.ply", "wb").write(
    b"\x00ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
    b"element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    b"1 1 0\n1 2 0\n0 2 0\n0 0 0\n2 0 0\n2 1 0\n6 0 1 2 3 4 5\n")
open(f"{out}/cube.obj", "wb").write(
    b"\x01# cube\nmtllib cube.mtl\no Cube\nv 1 1 -1\nv 1 -1 -1\nv 1 1 1\nv 1 -1 1\nv -1 1 -1\nv -1 -1 -1\n"
    b"v -1 1 1\nv -1 -1 1\nvt 0.5 0.5\nvn 0 1 0\nusemtl m\ns off\ng side\nf 1/1/1 5/1/1 7/1/1 3/1/1\n"
    b"f 4//1 3//1 7//1 8//1\nf 8/1 7/1 5/1 6/1\nf 6 2 4 8\nf -7 -8 -6 -5\nf -3 -4 -8 -7\n")
open(f"{out}/quads.off", "wb").write(
    b"\x03OFF\n# a closed cube of quads\n8 6 12\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
    b"4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n")
PY
# Triangle pairs (18 little-endian floats): crossing, touching at a vertex, coplanar overlapping, apart.
python3 - "$seeds/triangle_fuzzer" <<'PY'
import struct, sys
pairs = {
    "crossing": [0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, -0.5, 0.3, 0.2, 0.5, 0.2, 0.3, 0.5],
    "vertex": [0, 0, 0, 1, 0, 0, 0, 1, 0, 0.25, 0.25, 0, 1, 1, 1, 0, 1, 1],
    "coplanar": [0, 0, 0, 1, 0, 0, 0, 1, 0, 0.5, 0.5, 0, -0.5, 0.5, 0, 0.5, -0.5, 0],
    "apart": [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1],
    "far": [1e5, 1e5, 1e5, 1e5 + 1, 1e5, 1e5, 1e5, 1e5 + 1, 1e5, 1e5 + 0.2, 1e5 + 0.2, 1e5 - 0.5, 1e5 + 0.3,
            1e5 + 0.2, 1e5 + 0.5, 1e5 + 0.2, 1e5 + 0.3, 1e5 + 0.5],
}
for name, values in pairs.items():
    with open(f"{sys.argv[1]}/{name}", "wb") as out:
        out.write(struct.pack("<18f", *values))
PY

status=0
for fuzzer in "${fuzzers[@]}"; do
  corpus="$build/corpus/$fuzzer"
  artifacts="$build/artifacts/$fuzzer"
  mkdir -p "$corpus" "$artifacts"
  echo "fuzz.sh: $fuzzer for $seconds s (corpus $corpus)"
  # max_len: the seed meshes are 18-23 kB; longer inputs only slow the loader down.
  dictionary=()
  [ -f "$root/tests/fuzz/$fuzzer.dict" ] && dictionary=(-dict="$root/tests/fuzz/$fuzzer.dict")
  if ! "$build/$fuzzer" "$corpus" "$seeds/$fuzzer" -max_total_time="$seconds" -max_len=32768 -rss_limit_mb=2048 \
      -timeout=10 -artifact_prefix="$artifacts/" -print_final_stats=1 "${dictionary[@]}" 2>"$build/$fuzzer.log"; then
    echo "fuzz.sh: $fuzzer found a failure; input in $artifacts, log in $build/$fuzzer.log"
    tail -n 40 "$build/$fuzzer.log"
    status=1
  else
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build/$fuzzer.log" | sed "s/^/  $fuzzer /"
  fi
done
exit $status
