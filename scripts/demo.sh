#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, and runs gpucol-demo (default: the 10-box stack
# with gpucol's collision; arguments go to gpucol-demo, e.g. --scene pile, --backend gimpact, --help).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGPUCOL_BUILD_TESTS=OFF -DGPUCOL_BUILD_DEMOS=ON
exec "$root/build/release/demos/gpucol-demo" "$@"
