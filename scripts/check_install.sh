#!/usr/bin/env bash
# Installs the release build into a staging prefix and builds tests/install_consumer against it with
# find_package(gpucol), then runs it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
stage="$root/build/stage"
rm -rf "$stage" "$root/build/install_consumer"
cmake --install "$root/build/release" --prefix "$stage" >/dev/null
cmake -S "$root/tests/install_consumer" -B "$root/build/install_consumer" -DCMAKE_PREFIX_PATH="$stage" >/dev/null
cmake --build "$root/build/install_consumer" -j "$(nproc)" >/dev/null
"$root/build/install_consumer/gpucol_install_consumer"
