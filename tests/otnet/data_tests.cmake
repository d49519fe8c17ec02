# OTNet data (thesis ch 6): the Occ-Traj120 reader and map splits, and the synthetic rooms and
# corridors generator with its planner, each against an independent computation.
foresight_add_test(otnet_data_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/data_test.cc ${CMAKE_CURRENT_SOURCE_DIR}/otnet/synthetic_rooms_test.cc
  DEPS foresight_datasets foresight_test_util
  PREFIX otnet.)
