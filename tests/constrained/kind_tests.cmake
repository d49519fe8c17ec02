foresight_add_test(constrained_kind_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/constrained/kind_test.cc
  DEPS foresight_training_constrained foresight_kinds foresight_test_util
  PREFIX constrained.)
