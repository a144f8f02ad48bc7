#!/usr/bin/env bash
# The README's headline figures from one machine and one commit: mesh pairs beside GImpact (the thesis scene,
# armadillo-27674 and -399904), the broad phase beside btDbvt at 100K and 1M moving boxes, and the stack and
# pile worlds beside GImpact. Writes CSVs and the printed tables to demos/bench/results/headline/<name>/
# (default name: the CPU model's first word, the core count and the short commit).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGPUCOL_BUILD_DEMOS=ON >/dev/null
bench="$root/build/release/demos/gpucol-bench"
# The model's first word that is not the maker's or a trade mark: "xeon", "epyc", ...
cpu="$(awk -F': ' '/model name/ {print tolower($2); exit}' /proc/cpuinfo | tr -c 'a-z0-9\n' ' ' |
  tr ' ' '\n' | grep -v -x -E 'intel|amd|r|tm|cpu|processor|' | head -1 || true)"
name="${1:-${cpu:-cpu}-$(nproc)core-$(git -C "$root" rev-parse --short HEAD)}"
out="$root/demos/bench/results/headline/$name"
mkdir -p "$out"
{
  echo "commit $(git -C "$root" rev-parse HEAD)$(git -C "$root" diff --quiet || echo ' (with local changes)')"
  echo "cpu $(awk -F': ' '/model name/ {print $2; exit}' /proc/cpuinfo), $(nproc) cores"
  echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$out/machine.txt"
"$bench" meshpair --mesh armadillo-27674.ply armadillo-399904.ply --runs 5 --csv "$out/meshpair.csv" | tee "$out/meshpair.txt"
"$bench" broadphase --n 100000,1000000 --scenes uniform --run cpu,dbvt --steps 5 --peer-max 1000000 --interleave \
  --csv "$out/broadphase.csv" | tee "$out/broadphase.txt"
"$bench" world --scenes stack pile --csv "$out/world.csv" | tee "$out/world.txt"
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$out/machine.txt"
