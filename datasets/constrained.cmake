# Scenes with maps for structurally constrained prediction (thesis ch 7): THOR, ETH, Occ-Traj120
# and synthetic maps with tracks, their loading report and scene/track splits.
target_sources(foresight_datasets PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/map_tracks.cc)
