# OTNet data (thesis ch 6): the Occ-Traj120 reader and splits, synthetic rooms and corridors.
target_sources(foresight_datasets PRIVATE
  ${CMAKE_CURRENT_SOURCE_DIR}/occ_traj.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/synthetic_rooms.cc)
target_link_libraries(foresight_datasets PUBLIC opencv_imgproc)
