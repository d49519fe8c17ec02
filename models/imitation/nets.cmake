# LibTorch learners of diffeomorphic templates: the RBF flow (trained through its Euler
# integration), the Euclideanizing-Flows baseline and the ImitationTask the trainer runs.
# (foresight_trainer is defined later, in training/; CMake resolves the name at generate time.)
foresight_add_library(foresight_models_imitation_nets
  SOURCES imitation/flow_net.cc imitation/eflow_net.cc
  DEPS foresight_imitation_eflow foresight_models_imitation foresight_trainer ${TORCH_LIBRARIES})
