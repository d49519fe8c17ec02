target_sources(foresight_models_occupancy PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/occupancy/coupled_bhm.cc)
