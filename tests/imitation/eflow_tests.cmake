# Euclideanizing-Flows engine (torch-free): Jacobian, inverse, artifact round trip and bad files.
foresight_add_test(imitation_eflow_tests
  SOURCES imitation/eflow_test.cc
  DEPS foresight_imitation_eflow foresight_test_util
  PREFIX imitation.)
