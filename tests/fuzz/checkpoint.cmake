# The LibTorch checkpoint reader: a regression ctest over corpus/checkpoint/ in the LibTorch build,
# fuzzed by fuzz_main.cc's mutations (scripts/fuzz.sh); never a libFuzzer binary.
if(FORESIGHT_WITH_TORCH)
  foresight_add_fuzz_target(checkpoint LIBFUZZER_OFF
    SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/checkpoint.cc
    DEPS foresight_trainer)
endif()
