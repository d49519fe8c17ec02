# Diffeomorphic templates engine (thesis ch 8, torch-free): RBF grid and flows, the occupancy
# field, obstacle/bias transforms and their composition, the diffeo_template artifact.
foresight_add_library(foresight_imitation
  SOURCES rbf_grid.cc rbf_flow.cc occupancy_field.cc transforms.cc template_artifact.cc
  DEPS foresight_inference)
