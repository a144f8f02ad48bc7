#!/usr/bin/env bash
# The GPU check, in two halves (issue 56):
#
#   scripts/gpu-check.sh pack [PACK]       here (Debian): builds the Release tree and packs into PACK (default
#                                          build/gpu-check) what a bare x86-64 machine with an NVIDIA driver but
#                                          no Debian packages needs: the OpenCL test and bench binaries, clinfo,
#                                          their shared libraries (ocl-icd's libOpenCL.so.1, Bullet, TBB,
#                                          libstdc++ and glibc with its loader), the meshes, and this script.
#   bash PACK/gpu-check.sh run [OUT]       there: makes an ICD file for the machine's libnvidia-opencl.so.1,
#                                          lists the devices, runs the OpenCL tests on the GPU only (a skipped
#                                          test counts as a failure), then the GPU benchmarks, writing logs and
#                                          CSVs to OUT (default PACK/results) and a summary at its end.
#   scripts/gpu-check.sh rehearse          here: packs, then runs the "there" half against PoCL's CPU device
#                                          (its ICD only, the quick benchmarks), as the GPU would see it.
#
# Budget there: the whole run stays inside 8 minutes (GPUCOL_CHECK_SECONDS, each step its own timeout).
set -uo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

# Tests that need PoCL's CPU device: they check the host's heap, which holds a GPU's buffers only there. Every
# other test of the OpenCL suite must pass on the GPU.
cpu_device_only='OpenClPairFinderMemory.*'
# The Bullet suite's tests of the OpenCL pair finder and of Backend::Auto on the device.
bullet_opencl_tests='GridBroadphase.PairCacheMatchesBruteForceOverStepsOnOpenCl:GridBroadphase.OpenClKeepsItsGridWhileProxiesAreAdded:GridBroadphase.ProxiesCreatedAfterResetPoolAreSearchedOnOpenCl:GridBroadphase.AutoBackendStartsOnTheCpuAndMeasuresOnlyOnAGpu'
# Auto's first start of OpenCL: a process of its own, in which nothing started OpenCL before.
bullet_auto_start='SkipCounters.LargeBatchUnderAutoStartsOpenClOnlyForAGpu'

pack() {
  local root pack build
  root="$(cd "$here/.." && pwd)"
  pack="${1:-$root/build/gpu-check}"
  build="$root/build/release"
  "$root/scripts/build.sh" -DGPUCOL_BUILD_TESTS=ON -DGPUCOL_BUILD_DEMOS=ON >/dev/null || return 1
  rm -rf "$pack"
  mkdir -p "$pack/bin" "$pack/lib/glibc" "$pack/meshes"
  local binaries=("$build/tests/gpucol_test_opencl" "$build/tests/gpucol_test_bullet" \
                  "$build/demos/gpucol-bench" "$(command -v clinfo)")
  for b in "${binaries[@]}"; do
    [ -x "$b" ] || { echo "gpu-check: $b is missing (is clinfo installed? scripts/deps.sh)"; return 1; }
    cp "$b" "$pack/bin/"
    strip --strip-unneeded "$pack/bin/$(basename "$b")"
  done
  # Every shared library the binaries load, as this machine resolves it. glibc and its loader go apart: they
  # are used only where the machine's own glibc is older than the one the binaries were built against.
  local lib
  for lib in $(ldd "${binaries[@]}" | awk '/=>/ && $3 ~ /^\// {print $3} /^\t\/.*ld-linux/ {print $1}' | sort -u); do
    case "$(basename "$lib")" in
      ld-linux*|libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*) cp -L "$lib" "$pack/lib/glibc/" ;;
      *) cp -L "$lib" "$pack/lib/" ;;
    esac
  done
  # b3GpuGridBroadphase's OpenCL wrangler (clew) opens libOpenCL.so by that name.
  cp -L /usr/lib/x86_64-linux-gnu/libOpenCL.so.1 "$pack/lib/libOpenCL.so"
  strip --strip-unneeded "$pack"/lib/*.so* 2>/dev/null || true
  local meshes="${GPUCOL_MESH_DIR:-$root/../shared/data/meshes}"
  for m in armadillo-2766 armadillo-27674 armadillo-99976 armadillo-399904 bunny-948 torus-1152; do
    cp "$meshes/$m.ply" "$pack/meshes/" || return 1
  done
  cp "$here/gpu-check.sh" "$pack/"
  getconf GNU_LIBC_VERSION | awk '{print $2}' >"$pack/glibc-version"
  git -C "$root" rev-parse --short HEAD >"$pack/commit" 2>/dev/null || echo unknown >"$pack/commit"
  git -C "$root" diff --quiet 2>/dev/null || echo "+uncommitted" >>"$pack/commit"
  echo "gpu-check: packed $(du -sh "$pack" | cut -f1) into $pack"
}

run_there() {
  local pack out
  pack="$here"
  out="${1:-$pack/results}"
  mkdir -p "$out"
  local summary="$out/summary.txt"
  : >"$summary"
  say() { echo "$*" | tee -a "$summary"; }
  local started=$SECONDS budget="${GPUCOL_CHECK_SECONDS:-480}"
  left() { echo $((budget - (SECONDS - started))); }
  say "gpu-check: commit $(tr '\n' ' ' <"$pack/commit"), $(date -u +%FT%TZ), $(uname -m), $(nproc) cores"

  # Which loader: the machine's own where its glibc is at least the packed one, else the packed loader.
  local packed_glibc system_glibc runner=()
  packed_glibc="$(cat "$pack/glibc-version")"
  system_glibc="$(getconf GNU_LIBC_VERSION 2>/dev/null | awk '{print $2}')"
  local libpath="$pack/lib"
  if [ "${GPUCOL_CHECK_ICD:-nvidia}" = nvidia ]; then
    local driver=""
    driver="$(ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1 / {print $NF; exit}')"
    if [ -z "$driver" ]; then
      driver="$(find /usr/lib /usr/lib64 /usr/local/nvidia /usr/lib/x86_64-linux-gnu -name 'libnvidia-opencl.so.1' 2>/dev/null | head -1)"
    fi
    if [ -z "$driver" ]; then
      say "gpu-check: FAIL: no libnvidia-opencl.so.1 on this machine (ldconfig -p, /usr/lib*, /usr/local/nvidia)"
      return 1
    fi
    mkdir -p "$out/icd"
    echo "$driver" >"$out/icd/nvidia.icd"
    export OCL_ICD_VENDORS="$out/icd"
    libpath="$libpath:$(dirname "$driver")"
    export GPUCOL_OPENCL_DEVICE="${GPUCOL_OPENCL_DEVICE:-NVIDIA}"
    say "gpu-check: ICD $out/icd/nvidia.icd -> $driver"
    command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee -a "$summary"
  else
    export OCL_ICD_VENDORS="/etc/OpenCL/vendors/pocl.icd"
    export GPUCOL_OPENCL_DEVICE="${GPUCOL_OPENCL_DEVICE:-pthread}"
  fi
  if [ -n "$system_glibc" ] && [ -n "$packed_glibc" ] &&
     [ "$(printf '%s\n%s\n' "$packed_glibc" "$system_glibc" | sort -V | head -1)" = "$packed_glibc" ]; then
    export LD_LIBRARY_PATH="$libpath${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    say "gpu-check: the machine's glibc $system_glibc (packed $packed_glibc): its own loader"
  else
    runner=("$pack/lib/glibc/ld-linux-x86-64.so.2" --library-path "$libpath:$pack/lib/glibc")
    say "gpu-check: the machine's glibc ${system_glibc:-unknown} is older than the packed $packed_glibc: the packed loader"
  fi
  export GPUCOL_MESH_DIR="$pack/meshes"
  local status=0

  # 1. Devices.
  timeout 60 "${runner[@]}" "$pack/bin/clinfo" >"$out/clinfo.txt" 2>&1
  timeout 30 "${runner[@]}" "$pack/bin/clinfo" -l 2>&1 | tee -a "$summary"
  grep -E '^\s+(Device Name|Driver Version|Max compute units|Max memory allocation|Global memory size|Local memory size|Max work group size|Preferred work group size multiple|Device Type)' \
    "$out/clinfo.txt" | head -20 | tee -a "$summary"

  # 2. The OpenCL tests on the GPU alone, each shape the device's own (GPUCOL_OPENCL_SHAPE unset) and both
  # forced; a skipped test is a failure: the device is there to be tested.
  run_tests() {
    local name="$1" binary="$2" filter="$3" seconds="$4"
    local log="$out/test-$name.log"
    timeout "$seconds" "${runner[@]}" "$pack/bin/$binary" --gtest_filter="$filter" \
      --gtest_output="xml:$out/test-$name.xml" >"$log" 2>&1
    local rc=$?
    local passed skipped failed
    passed="$(grep -c '^\[       OK \]' "$log")"
    skipped="$(grep -c '^\[  SKIPPED \]' "$log")"
    failed="$(grep -c '^\[  FAILED  \]' "$log")"
    if [ "$rc" -eq 0 ] && [ "$skipped" -eq 0 ] && [ "$passed" -gt 0 ]; then
      say "gpu-check: tests $name: $passed passed"
    else
      say "gpu-check: FAIL: tests $name: exit $rc, $passed passed, $failed failed lines, $skipped skipped"
      grep -E '^\[  (FAILED|SKIPPED) \]|Failure|error' "$log" | head -20 | tee -a "$summary"
      tail -5 "$log" | tee -a "$summary"
      status=1
    fi
  }
  local test_seconds=$(( $(left) / 3 ))
  run_tests opencl gpucol_test_opencl "*-$cpu_device_only" "$test_seconds"
  run_tests bullet-opencl gpucol_test_bullet "$bullet_opencl_tests" 120
  run_tests bullet-auto-start gpucol_test_bullet "$bullet_auto_start" 60
  # The CPU device's shapes on the GPU too: both must stay correct wherever they run.
  GPUCOL_OPENCL_SHAPE=cpu run_tests opencl-cpu-shape gpucol_test_opencl "MeshPipeline.*:OpenClPairFinder.*:OpenClRadixSort.*:*OpenClScan*" \
    "$(( $(left) / 4 ))"

  # 3. Benchmarks (each bounded; whatever time is left goes to the next).
  local quick="${GPUCOL_CHECK_QUICK:-0}"
  bench() {
    local name="$1" seconds="$2"
    shift 2
    [ "$(left)" -gt 20 ] || { say "gpu-check: bench $name skipped: the time budget is spent"; status=1; return; }
    [ "$seconds" -gt "$(left)" ] && seconds="$(left)"
    say "gpu-check: bench $name ($*)"
    timeout "$seconds" "${runner[@]}" "$pack/bin/gpucol-bench" "$@" >"$out/bench-$name.txt" 2>&1
    local rc=$?
    cat "$out/bench-$name.txt" >>"$summary"
    if [ "$rc" -ne 0 ]; then say "gpu-check: FAIL: bench $name exit $rc"; status=1; fi
  }
  if [ "$quick" = 1 ]; then
    bench meshpair 120 meshpair --backend opencl --no-variants --runs 3 --mesh-dir "$pack/meshes" \
      --mesh armadillo-2766.ply
    bench meshbatch 60 meshbatch --mesh-dir "$pack/meshes" --pairs 20 --runs 3
    bench broadphase 120 broadphase --n 20000 --scenes uniform --run cpu,opencl,b3 --steps 3 --interleave \
      --csv "$out/broadphase.csv"
    bench crossover 120 crossover --mesh-dir "$pack/meshes" --quick --csv "$out/crossover.csv"
  else
    bench meshpair 100 meshpair --backend opencl --runs 7 --mesh-dir "$pack/meshes"
    bench broadphase 120 broadphase --n 100000,1000000 --scenes uniform,mixed --run cpu,opencl,b3 --steps 7 --stages \
      --interleave --peer-max 1000000 --csv "$out/broadphase.csv"
    bench meshbatch 40 meshbatch --mesh-dir "$pack/meshes" --pairs 100 --runs 7
    bench crossover 90 crossover --mesh-dir "$pack/meshes" --csv "$out/crossover.csv"
    # The CPU device's shapes on the same GPU, to weigh the two.
    GPUCOL_OPENCL_SHAPE=cpu bench meshpair-cpu-shape 60 meshpair --backend opencl --no-variants --runs 5 \
      --mesh-dir "$pack/meshes"
    GPUCOL_OPENCL_SHAPE=cpu bench broadphase-cpu-shape 60 broadphase --n 100000,1000000 --scenes uniform \
      --run opencl --steps 7
  fi
  say "gpu-check: $([ $status -eq 0 ] && echo PASS || echo FAIL) in $((SECONDS - started)) s; results in $out"
  return $status
}

case "${1:-}" in
  pack) shift; pack "$@" ;;
  run) shift; run_there "$@" ;;
  rehearse)
    root="$(cd "$here/.." && pwd)"
    pack "$root/build/gpu-check" || exit 1
    GPUCOL_CHECK_ICD=pocl GPUCOL_CHECK_QUICK=1 GPUCOL_CHECK_SECONDS="${GPUCOL_CHECK_SECONDS:-1500}" \
      bash "$root/build/gpu-check/gpu-check.sh" run "$root/build/gpu-check-rehearsal"
    ;;
  *) sed -n '2,15p' "$0"; exit 2 ;;
esac
