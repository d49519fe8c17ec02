# OTNet's pipeline pieces (pruned MTD, database choice). Needs the LibTorch build (the training lib).
foresight_add_test(otnet_training_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/pipeline_test.cc
  DEPS foresight_training_otnet foresight_test_util
  PREFIX otnet.)
