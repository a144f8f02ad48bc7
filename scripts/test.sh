#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test suite, then checks that
# an installed gpucol is found by an outside CMake project.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh" -DGPUCOL_BUILD_TESTS=ON -DGPUCOL_BUILD_DEMOS=ON
ctest --test-dir "$root/build/release" --output-on-failure -j "$(nproc)" --timeout 600
"$root/scripts/check_install.sh"
