# OTNet (thesis ch 6): data preparation, training/export, evaluation against k-NN and the mean
# trajectory, transfer to a real occupancy map, plots, the kind and its bench.
foresight_add_library(foresight_training_otnet
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/config.cc ${CMAKE_CURRENT_SOURCE_DIR}/otnet/data.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/otnet/train.cc ${CMAKE_CURRENT_SOURCE_DIR}/otnet/eval.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/otnet/task.cc ${CMAKE_CURRENT_SOURCE_DIR}/otnet/transfer.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/otnet/plots.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/otnet/pipeline.cc ${CMAKE_CURRENT_SOURCE_DIR}/otnet/kind.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/otnet/bench.cc
  DEPS foresight_image_io foresight_trainer foresight_training_core foresight_models_otnet_nets foresight_otnet
       foresight_datasets opencv_core opencv_imgproc opencv_imgcodecs ${TORCH_LIBRARIES})
