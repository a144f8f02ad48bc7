#!/usr/bin/env bash
# Builds gpucol and its tests with AddressSanitizer and UndefinedBehaviorSanitizer (build/sanitize) and runs
# every test suite under them. Slower than scripts/test.sh; run before merging changes to the core.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
GPUCOL_BUILD_NAME=sanitize GPUCOL_BUILD_TYPE=Debug "$root/scripts/build.sh" \
  -DGPUCOL_SANITIZE=ON -DGPUCOL_BUILD_TESTS=ON -DGPUCOL_BUILD_DEMOS=OFF
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$root/build/sanitize" --output-on-failure -j "$(nproc)" --timeout 1200
