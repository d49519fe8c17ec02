# LibTorch learners: RbfFlowNet and EFlowNet against autograd, finite differences and training;
# parity with the torch-free engines (RbfFlow when foresight_imitation is part of the build).
foresight_add_test(imitation_nets_tests
  SOURCES imitation/flow_net_test.cc imitation/eflow_net_test.cc
  DEPS foresight_models_imitation_nets foresight_training_imitation_task foresight_test_util
  PREFIX imitation.)
if(TARGET foresight_imitation)
  target_link_libraries(imitation_nets_tests PRIVATE foresight_imitation)
  target_compile_definitions(imitation_nets_tests PRIVATE FORESIGHT_HAVE_RBF_FLOW_ENGINE=1)
endif()
