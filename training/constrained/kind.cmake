# Structurally constrained prediction (thesis ch 7): data, maps, evaluation (prior vs optimised vs
# KTM, CV, naive), plots, the kind. The learners are in learners.cmake.
foresight_add_library(foresight_training_constrained
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/constrained/config.cc ${CMAKE_CURRENT_SOURCE_DIR}/constrained/data.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/constrained/eval.cc ${CMAKE_CURRENT_SOURCE_DIR}/constrained/plots.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/constrained/pipeline.cc ${CMAKE_CURRENT_SOURCE_DIR}/constrained/kind.cc
  DEPS foresight_image_io foresight_training_constrained_learners foresight_training_core foresight_constrained
       foresight_models_occupancy foresight_map_canvas foresight_datasets opencv_core opencv_imgproc
       opencv_imgcodecs ${TORCH_LIBRARIES})
