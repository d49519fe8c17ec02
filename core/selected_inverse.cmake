target_sources(foresight_core PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/selected_inverse.cc)
