#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, and runs gpucol-demo (default: the 10-box stack
# with gpucol's collision; arguments go to gpucol-demo, e.g. --scene pile, --backend gimpact, --help). It also
# writes a picture of the final scene and a plot of heights and kinetic energy over time into
# build/release/demo-output/ (GPUCOL_DEMO_OUTPUT names another folder), and says where.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGPUCOL_BUILD_TESTS=OFF -DGPUCOL_BUILD_DEMOS=ON
out="${GPUCOL_DEMO_OUTPUT:-$root/build/release/demo-output}"
mkdir -p "$out"
rm -f "$out/scene.png" "$out/plot.png"
status=0
"$root/build/release/demos/gpucol-demo" --picture "$out/scene.png" --plot "$out/plot.png" "$@" || status=$?
if [ -f "$out/scene.png" ] && [ -f "$out/plot.png" ]; then
  echo "demo.sh: picture of the final scene: $out/scene.png"
  echo "demo.sh: heights and kinetic energy over time: $out/plot.png"
fi
exit "$status"
