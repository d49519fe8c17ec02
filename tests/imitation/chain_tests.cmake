# JACO serial-chain kinematics (against KDL and finite differences) and the C-space obstacle
# transform and system. Own binary: cspace_test.cc replaces the global allocators to count them.
find_package(orocos_kdl REQUIRED)
foresight_add_test(imitation_chain_tests
  SOURCES imitation/serial_chain_test.cc imitation/cspace_test.cc
  DEPS foresight_imitation_chain foresight_models_imitation foresight_test_util ${orocos_kdl_LIBRARIES}
  PREFIX imitation.)
