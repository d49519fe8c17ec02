# JACO serial-chain kinematics (urdfdom) and the C-space obstacle transform and system (thesis ch 8).
find_package(urdfdom REQUIRED)
foresight_add_library(foresight_imitation_chain
  SOURCES serial_chain.cc cspace.cc
  DEPS foresight_imitation urdfdom::urdfdom_model)
