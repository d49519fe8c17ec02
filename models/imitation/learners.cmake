# Diffeomorphic templates, torch-free learners: the obstacle occupancy fit (IRLS).
foresight_add_library(foresight_models_imitation
  SOURCES imitation/occupancy_fit.cc
  DEPS foresight_imitation)
