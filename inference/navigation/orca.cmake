target_sources(foresight_navigation PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/orca.cc)
