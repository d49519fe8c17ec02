# The learners of constrained prediction (prior, KTM, naive): tiny trainings on synthetic windows,
# KTM features against a direct computation, engine vs LibTorch parity, resume. Needs LibTorch.
foresight_add_test(constrained_learners_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/constrained/learners_test.cc
  DEPS foresight_training_constrained_learners foresight_test_util
  PREFIX constrained.)
