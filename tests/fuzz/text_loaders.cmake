# Fuzz targets of the text loaders (issue 18): one libFuzzer target per file text_<name>.cc, seed
# inputs and regression inputs in corpus/<name>/. Included by tests/fuzz/CMakeLists.txt.
#
# config_yaml: the span and directional experiment configs live in LibTorch-only libraries
# (foresight_training_span / _directional), but their headers and Validate() are torch-free, so
# the target compiles their config.cc itself; the occupancy and navigation ones likewise (their
# libraries pull in the whole pipelines, which the config reader does not need).
set(FORESIGHT_TEXT_FUZZ_DIR ${CMAKE_CURRENT_SOURCE_DIR})

foresight_add_fuzz_target(config_yaml
  SOURCES ${FORESIGHT_TEXT_FUZZ_DIR}/text_config_yaml.cc
          ${PROJECT_SOURCE_DIR}/training/span/config.cc
          ${PROJECT_SOURCE_DIR}/training/directional/config.cc
          ${PROJECT_SOURCE_DIR}/training/occupancy/config.cc
          ${PROJECT_SOURCE_DIR}/training/navigation/config.cc
  DEPS foresight_datasets foresight_inference foresight_navigation foresight_models_occupancy)

foreach(name eth_ucy carmen directional_csv crowd_replay occ_traj lasa)
  foresight_add_fuzz_target(${name}
    SOURCES ${FORESIGHT_TEXT_FUZZ_DIR}/text_${name}.cc
    DEPS foresight_datasets)
endforeach()

foresight_add_fuzz_target(mbm_problem
  SOURCES ${FORESIGHT_TEXT_FUZZ_DIR}/text_mbm_problem.cc
  DEPS foresight_manipulation_world)

foresight_add_fuzz_target(urdf
  SOURCES ${FORESIGHT_TEXT_FUZZ_DIR}/text_urdf.cc
  DEPS foresight_manipulation_robot foresight_imitation_chain)
