# OTNet's LibTorch mixture density network: the NLL against a direct computation and finite
# differences, the export against the engine, a tiny training run, errors.
foresight_add_test(otnet_nets_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/otnet_net_test.cc
  DEPS foresight_training_otnet foresight_test_util
  PREFIX otnet.)
