# Demonstrations (LASA reader, preprocessing, synthetic and task-space demos) and the imitation
# metrics, each against an independent computation.
foresight_add_test(imitation_data_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/imitation/lasa_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/imitation/demonstrations_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/imitation/synthetic_demos_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/imitation/metrics_test.cc
  DEPS foresight_datasets foresight_imitation_metrics foresight_test_util
  PREFIX imitation.)
