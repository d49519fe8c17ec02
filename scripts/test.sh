#!/usr/bin/env bash
# Installs missing packages, builds Release and runs every test with ctest. The build includes the
# torch-free command line a -DFORESIGHT_WITH_TORCH=OFF build makes (tests run it and check it links
# no LibTorch); FORESIGHT_TEST_TORCH_OFF=1 also builds and tests that configuration on its own.
# Then the LibTorch-free tree again with Clang 14 under AddressSanitizer + UndefinedBehaviorSanitizer
# (build-sanitize/): its tests and every fuzz corpus (docs/robustness.md); FORESIGHT_SANITIZE_TESTS=0
# skips that part.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
PACKAGES+=(clang-14)
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
if [ "${FORESIGHT_SANITIZE_TESTS:-1}" = "1" ]; then
  # -O1: ASan's recommended level (the tests take 4 minutes), and a little quicker to compile.
  configure_and_build "$ROOT/build-sanitize" -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELEASE=-O1 -DNDEBUG" \
    -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF -DFORESIGHT_SANITIZE=ON
  # The format check is the main build's; everything else runs under the sanitizers.
  (cd "$ROOT/build-sanitize" &&
    ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1 LSAN_OPTIONS="suppressions=$ROOT/tests/fuzz/lsan.supp" \
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --output-on-failure -j 2 --timeout 900 -E '^format_check$')
fi
