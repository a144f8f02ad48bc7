#!/usr/bin/env bash
# Configures and builds gpucol into build/<name> (default: build/release). Extra arguments go to CMake.
# Used by demo.sh and test.sh; runs deps.sh first.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
name="${GPUCOL_BUILD_NAME:-release}"
"$root/scripts/deps.sh"
cmake -S "$root" -B "$root/build/$name" -DCMAKE_BUILD_TYPE="${GPUCOL_BUILD_TYPE:-Release}" "$@" >/dev/null
cmake --build "$root/build/$name" -j "$(nproc)"
