#pragma once
/// The HDF5 track store (schema: docs/dataset_schema.md, "foresight.tracks" version 1).

#include <string>

#include "datasets/tracks.h"

namespace foresight {

inline constexpr const char* kTrackStoreKind = "foresight.tracks";
inline constexpr std::int64_t kTrackStoreVersion = 1;

void WriteTrackStore(const std::string& path, const TrackSet& set);
/// Errors name the file and what is missing or inconsistent.
TrackSet ReadTrackStore(const std::string& path);

}  // namespace foresight
