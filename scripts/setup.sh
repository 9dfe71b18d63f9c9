#!/usr/bin/env bash
# Installs the Debian packages col0rme needs (only what is missing), then
# configures and builds into ./build. Safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."

PKGS=(build-essential cmake pkg-config libtiff-dev libtiff-tools libcjson-dev libpng-dev libfftw3-dev libdeflate-dev
      python3-numpy python3-tifffile python3-tqdm clang libclang-rt-14-dev libomp-14-dev
      libopenmpi-dev openmpi-bin
      python3-venv python3-pip python3-setuptools python3-wheel python3-pytest binutils
      default-jdk-headless imagej xvfb
      chromium python3-pil)

missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

BUILD=${BUILD:-build}
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j"$(nproc)"
