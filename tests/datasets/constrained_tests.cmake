# Scenes with maps for constrained prediction (thesis ch 7): raster orientation, the loading
# report, splits, the synthetic generator and (when ../shared/data is present) THOR and ETH.
foresight_add_test(map_tracks_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/datasets/map_tracks_test.cc
  DEPS foresight_datasets foresight_test_util
  PREFIX datasets.)
