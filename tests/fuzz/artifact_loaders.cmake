# Structure-aware fuzz targets of the HDF5 artifact loaders (issue 18): each writes a small valid
# artifact with the engine's own writer, applies 1 to 4 edits chosen by the input (h5_mutator.cc)
# and loads the edited copy; a model that loads answers one finite query that must be finite.
set(_art ${CMAKE_CURRENT_SOURCE_DIR})
foresight_add_fuzz_target(track_store
  SOURCES ${_art}/artifact_track_store.cc ${_art}/h5_mutator.cc DEPS foresight_datasets)
foresight_add_fuzz_target(span_artifact
  SOURCES ${_art}/artifact_span.cc ${_art}/h5_mutator.cc DEPS foresight_inference)
foresight_add_fuzz_target(directional_artifact
  SOURCES ${_art}/artifact_directional.cc ${_art}/h5_mutator.cc DEPS foresight_inference)
foresight_add_fuzz_target(occupancy_artifact
  SOURCES ${_art}/artifact_occupancy.cc ${_art}/h5_mutator.cc DEPS foresight_inference)
foresight_add_fuzz_target(otnet_artifact
  SOURCES ${_art}/artifact_otnet.cc ${_art}/h5_mutator.cc DEPS foresight_otnet)
foresight_add_fuzz_target(imitation_artifact
  SOURCES ${_art}/artifact_imitation.cc ${_art}/h5_mutator.cc
  DEPS foresight_imitation foresight_imitation_eflow)
foresight_add_fuzz_target(energy_artifact
  SOURCES ${_art}/artifact_energy.cc ${_art}/h5_mutator.cc DEPS foresight_manipulation_learning)
unset(_art)
