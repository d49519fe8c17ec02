# Structurally constrained prediction (thesis ch 7): the learners of the prior (SPAN mixture net),
# the KTM baseline and the naive network, trained from given windows and exported to the engines.
foresight_add_library(foresight_training_constrained_learners
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/learners.cc
          ${PROJECT_SOURCE_DIR}/models/constrained/naive_net.cc
  DEPS foresight_training_span foresight_trainer foresight_inference ${TORCH_LIBRARIES})
