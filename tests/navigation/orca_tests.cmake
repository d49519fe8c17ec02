# ORCA (issue 12): the half-plane program and crowds of agents running it. Torch-free.
foresight_add_test(navigation_orca_tests SOURCES navigation/orca_test.cc DEPS foresight_navigation foresight_test_util PREFIX navigation.)
