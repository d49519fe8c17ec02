# LibTorch learners of diffeomorphic templates: the RBF flow (trained through its Euler
# integration) and the Euclideanizing-Flows baseline. The trainer's task that fits them is
# training/diffeo/imitation_task.h (foresight_training_imitation_task).
foresight_add_library(foresight_models_imitation_nets
  SOURCES imitation/flow_net.cc imitation/eflow_net.cc
  DEPS foresight_imitation_eflow foresight_models_imitation ${TORCH_LIBRARIES})
