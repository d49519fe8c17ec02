# OTNet's mixture density network in LibTorch (its TrainingTask lives in training/otnet/task.h).
foresight_add_library(foresight_models_otnet_nets
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/otnet_net.cc
  DEPS foresight_otnet ${TORCH_LIBRARIES})
