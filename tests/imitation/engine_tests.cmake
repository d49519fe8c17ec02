# Diffeomorphic templates engine (thesis ch 8, torch-free): grid, flows, occupancy field and fit,
# transforms, the artifact, the flow's hand-written training objective.
foresight_add_test(imitation_engine_tests
  SOURCES imitation/rbf_flow_test.cc imitation/occupancy_field_test.cc
          imitation/transforms_test.cc imitation/template_artifact_test.cc
          imitation/flow_objective_test.cc
  DEPS foresight_models_imitation foresight_test_util
  PREFIX imitation.)
# Own binary: it replaces the global operator new to count allocations.
foresight_add_test(imitation_alloc_tests
  SOURCES imitation/imitation_alloc_test.cc
  DEPS foresight_models_imitation foresight_test_util
  PREFIX imitation.)
