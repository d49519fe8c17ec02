# Euclideanizing-Flows baseline engine (torch-free): coupling layers, Jacobian, artifact.
foresight_add_library(foresight_imitation_eflow
  SOURCES eflow.cc
  DEPS foresight_inference)
