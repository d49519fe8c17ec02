# Map encoding by Hausdorff similarities, the trajectory RBF basis, the trajectory metrics.
foresight_add_library(foresight_otnet_encoding
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/map_encoding.cc ${CMAKE_CURRENT_SOURCE_DIR}/trajectory_basis.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/trajectory_metrics.cc
  DEPS foresight_core foresight_imitation_metrics opencv_core opencv_imgproc)
