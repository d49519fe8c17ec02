foresight_add_library(foresight_constrained_cost
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/gauss_hermite.cc ${CMAKE_CURRENT_SOURCE_DIR}/component.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/collision_cost.cc
  DEPS foresight_inference)
