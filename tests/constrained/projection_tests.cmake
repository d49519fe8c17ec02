foresight_add_test(constrained_projection_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/constrained/kl_test.cc ${CMAKE_CURRENT_SOURCE_DIR}/constrained/projection_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/constrained/projection_cost_test.cc
  DEPS foresight_constrained foresight_test_util
  PREFIX constrained.)
