#!/usr/bin/env bash
# Installs every Debian package that gpucol needs to build, test and run its demos.
# Idempotent: does nothing when all of them are present.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libbullet-dev libbullet-extras-dev
  libeigen3-dev
  libtbb-dev
  ocl-icd-opencl-dev opencl-headers opencl-clhpp-headers pocl-opencl-icd clinfo
  libgtest-dev libgmock-dev
  libcli11-dev
  libstb-dev
  python3-matplotlib
  clang libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "deps.sh: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
