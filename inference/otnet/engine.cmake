# The OTNet engine: predict, condition, sample, collision-check; the artifact.
foresight_add_library(foresight_otnet
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet_model.cc
  DEPS foresight_otnet_encoding foresight_inference)
