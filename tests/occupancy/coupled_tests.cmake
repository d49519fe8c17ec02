# The learning Fast-BHM (coupled weights, learned bound; issue 11) and the selected inverse.
foresight_add_test(occupancy_coupled_tests
  SOURCES occupancy/coupled_bhm_test.cc core/selected_inverse_test.cc
  DEPS foresight_models_occupancy foresight_test_util
  PREFIX occupancy.)
