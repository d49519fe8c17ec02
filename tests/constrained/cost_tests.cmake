foresight_add_test(constrained_cost_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/constrained/gauss_hermite_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/constrained/collision_cost_test.cc
  DEPS foresight_constrained_cost foresight_test_util
  PREFIX constrained.)
foresight_add_test(constrained_cost_alloc_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/constrained/cost_alloc_test.cc
  DEPS foresight_constrained_cost foresight_test_util
  PREFIX constrained.)
