#!/usr/bin/env bash
# Installs missing packages, builds Release and runs every test with ctest. Then builds the
# LibTorch-free tree (a -DFORESIGHT_WITH_TORCH=OFF build) again with Clang 14 under AddressSanitizer
# + UndefinedBehaviorSanitizer (build-sanitize/) and runs its tests, the torch-free CLI end to end and
# every fuzz corpus (docs/robustness.md); the main build then leaves those torch-free tests to it
# (-DFORESIGHT_TORCH_FREE_TESTS=OFF: each is built once). FORESIGHT_SANITIZE_TESTS=0 skips the
# sanitizer build; the main build then builds and runs them itself. FORESIGHT_TEST_TORCH_OFF=1 also
# builds and tests the OFF configuration with the default compiler.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
[ "${FORESIGHT_SANITIZE_TESTS:-1}" != "1" ] || PACKAGES+=(clang-14)
install_missing
SANITIZE="${FORESIGHT_SANITIZE_TESTS:-1}"
configure_and_build "$ROOT/build" -DFORESIGHT_TORCH_FREE_TESTS="$([ "$SANITIZE" = 1 ] && echo OFF || echo ON)"
(cd "$ROOT/build" && ctest --output-on-failure -j 2 --timeout 900)
# The OFF configuration is always configured (seconds: catches CMake errors of that branch) and
# built and tested on its own on request.
cmake -S "$ROOT" -B "$ROOT/build-notorch" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF > /dev/null
if [ "${FORESIGHT_TEST_TORCH_OFF:-0}" = "1" ]; then
  configure_and_build "$ROOT/build-notorch" -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF
  (cd "$ROOT/build-notorch" && ctest --output-on-failure -j 2 --timeout 300)
fi
if [ "$SANITIZE" = "1" ]; then
  # -O1: ASan's recommended level (the tests take 5 minutes here; at -O0 24), and quicker to compile.
  configure_and_build "$ROOT/build-sanitize" -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELEASE=-O1 -DNDEBUG" \
    -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF -DFORESIGHT_SANITIZE=ON
  # Every test binary the main build left to this one must exist here (a torch-free test defined
  # only in LibTorch builds would otherwise run in neither).
  missing=()
  while read -r target; do
    ninja -C "$ROOT/build-sanitize" -t query "$target" > /dev/null 2>&1 || missing+=("$target")
  done < <(cat "$ROOT/build/tests_left_to_torch_free_build.txt" 2> /dev/null || true)
  if ((${#missing[@]})); then
    echo "test binaries neither build runs (define them outside if(FORESIGHT_WITH_TORCH)): ${missing[*]}" >&2
    exit 1
  fi
  # The format check is the main build's; everything else runs under the sanitizers.
  (cd "$ROOT/build-sanitize" &&
    ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1 LSAN_OPTIONS="suppressions=$ROOT/tests/fuzz/lsan.supp" \
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --output-on-failure -j 2 --timeout 900 -E '^format_check$')
fi
