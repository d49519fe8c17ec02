# The OTNet engine (thesis ch 6, torch-free): prediction, start conditioning, sampling with
# collision rejection, the artifact.
foresight_add_test(otnet_engine_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/otnet_model_test.cc
  DEPS foresight_otnet foresight_test_util
  PREFIX otnet.)
# Own binary: it replaces the global operator new (and malloc) to count allocations.
foresight_add_test(otnet_engine_alloc_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/otnet_alloc_test.cc
  DEPS foresight_otnet foresight_test_util
  PREFIX otnet.)
