#!/usr/bin/env bash
# Installs what shockmpm needs from Debian's packages (a no-op when all is there), then
# configures and builds. Sourced by scripts/quickstart.sh and scripts/test.sh.
#   BUILD_DIR    build directory (default build)
#   CMAKE_ARGS   extra cmake arguments
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# C++ build, plus Debian's Python 3 with numpy, h5py and matplotlib for the figure scripts
# (run them with /usr/bin/python3: a python3 earlier on PATH may lack these modules).
PACKAGES=(g++ cmake make pkg-config libeigen3-dev libhdf5-dev catch2 libbenchmark-dev
          libtomlplusplus-dev libcli11-dev python3 python3-numpy python3-h5py python3-matplotlib)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
JOBS="$(nproc)"
cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" ${CMAKE_ARGS:-} >/dev/null
cmake --build "$BUILD_DIR" -j "$JOBS" ${BUILD_TARGET:+--target $BUILD_TARGET}
