foresight_add_library(foresight_constrained
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/kl.cc ${CMAKE_CURRENT_SOURCE_DIR}/projection.cc
  DEPS foresight_constrained_cost ${NLOPT_LIBRARIES})
