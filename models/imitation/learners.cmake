# Diffeomorphic templates, torch-free learners: the obstacle occupancy fit (IRLS) and the RBF
# flow's training objective with its hand-written gradient.
foresight_add_library(foresight_models_imitation
  SOURCES imitation/occupancy_fit.cc imitation/flow_objective.cc
  DEPS foresight_imitation)
