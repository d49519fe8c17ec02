foresight_add_test(constrained_runtime_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/constrained/distribution_projector_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/constrained/prediction_metrics_test.cc
  DEPS foresight_constrained foresight_test_util
  PREFIX constrained.)
