#!/usr/bin/env bash
# Shared set-up of run.sh and test.sh: install missing Debian packages, configure, build Release.
# Usage: source scripts/setup.sh [extra cmake args]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PACKAGES=(build-essential cmake ninja-build pkg-config libtorch-dev libeigen3-dev libopencv-dev
          libnlopt-cxx-dev libompl-dev libhdf5-dev libyaml-cpp-dev libcli11-dev libgtest-dev
          libgmock-dev libbenchmark-dev liboctomap-dev clang-format
          liburdfdom-dev liborocos-kdl-dev libfcl-dev libgloo-dev libopenblas0-serial)

install_missing() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "installing: ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
}

# configure_and_build BUILD_DIR [cmake args...]
configure_and_build() {
  local dir="$1"; shift
  cmake -S "$ROOT" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
  cmake --build "$dir" -j "${FORESIGHT_JOBS:-$(nproc)}"
}
