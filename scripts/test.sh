#!/usr/bin/env bash
# Installs missing packages, builds Release and runs every test with ctest; then builds the
# LibTorch-free configuration (inference must build and pass without LibTorch) and runs its tests.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
install_missing
configure_and_build "$ROOT/build"
(cd "$ROOT/build" && ctest --output-on-failure -j 2 --timeout 900)
configure_and_build "$ROOT/build-notorch" -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF
(cd "$ROOT/build-notorch" && ctest --output-on-failure -j 2 --timeout 300)
