# Metrics of generated motions: arc-length resampling, discrete Frechet distance, trajectory
# distance, maximum collision depth against spheres and capped cylinders (thesis ch 8 evaluation).
foresight_add_library(foresight_imitation_metrics
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/metrics.cc
  DEPS foresight_core Eigen3::Eigen)
