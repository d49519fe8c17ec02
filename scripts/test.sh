#!/usr/bin/env bash
# Installs missing packages, builds Release and runs every test with ctest. The build includes the
# torch-free command line a -DFORESIGHT_WITH_TORCH=OFF build makes (tests run it and check it links
# no LibTorch); FORESIGHT_TEST_TORCH_OFF=1 also builds and tests that configuration on its own.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
install_missing
configure_and_build "$ROOT/build"
(cd "$ROOT/build" && ctest --output-on-failure -j 2 --timeout 900)
# The OFF configuration is always configured (seconds: catches CMake errors of that branch) and
# built and tested on its own on request.
cmake -S "$ROOT" -B "$ROOT/build-notorch" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF > /dev/null
if [ "${FORESIGHT_TEST_TORCH_OFF:-0}" = "1" ]; then
  configure_and_build "$ROOT/build-notorch" -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF
  (cd "$ROOT/build-notorch" && ctest --output-on-failure -j 2 --timeout 300)
fi
