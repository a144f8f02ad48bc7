#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, and runs the demo on a built-in scene.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGPUCOL_BUILD_TESTS=OFF -DGPUCOL_BUILD_DEMOS=ON
if [ -x "$root/build/release/demos/gpucol-demo" ]; then
  exec "$root/build/release/demos/gpucol-demo" "$@"
fi
# Until the falling-stack demo exists, the demo is the mesh-pair benchmark on a built-in scene.
exec "$root/build/release/demos/gpucol-bench" meshpair --builtin "$@"
