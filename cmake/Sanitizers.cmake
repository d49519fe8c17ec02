# Sanitizer and fuzzing configurations (issue: nothing lost, nothing silently wrong).
#   -DFORESIGHT_SANITIZE=ON  AddressSanitizer + UndefinedBehaviorSanitizer on every target (any compiler
#                            that supports them; CI uses Clang 14 on the LibTorch-free build).
#   -DFORESIGHT_FUZZ=ON      Clang only: also instruments everything for libFuzzer and makes the fuzz
#                            targets of tests/fuzz/ real fuzzers (scripts/fuzz.sh). Implies SANITIZE.
# Without FUZZ, every fuzz target is still built as a regression runner over its corpus (a ctest).
option(FORESIGHT_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(FORESIGHT_FUZZ "Build the libFuzzer targets of tests/fuzz (Clang; implies FORESIGHT_SANITIZE)" OFF)

if(FORESIGHT_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "FORESIGHT_FUZZ needs Clang (libFuzzer); configure with "
                        "-DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_C_COMPILER=clang-14 (scripts/fuzz.sh does)")
  endif()
  set(FORESIGHT_SANITIZE ON)
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()

if(FORESIGHT_SANITIZE)
  # Recoverable UBSan reports would let a test pass with undefined behaviour: make them fatal.
  set(FORESIGHT_SANITIZER_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=undefined
                                -fno-omit-frame-pointer)
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    list(APPEND FORESIGHT_SANITIZER_FLAGS -gline-tables-only)  # line numbers in reports, cheaply
  endif()
  add_compile_options(${FORESIGHT_SANITIZER_FLAGS})
  add_link_options(-fsanitize=address,undefined)
  # The allocation counter of the no-allocation tests counts malloc through ASan's allocator hook
  # instead of interposing it (tests/alloc_counter.h); this tells it.
  add_compile_definitions(FORESIGHT_SANITIZE=1)
endif()
