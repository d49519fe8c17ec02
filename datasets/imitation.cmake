# Demonstrations for diffeomorphic templates (thesis ch 8): common types and preprocessing, the LASA
# handwriting reader, synthetic 2-D shapes and JACO task-space demos.
target_sources(foresight_datasets PRIVATE
  ${CMAKE_CURRENT_SOURCE_DIR}/lasa.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/demonstrations.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/synthetic_demos.cc)
