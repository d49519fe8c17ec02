#include "datasets/pedestrian_data.h"

#include <cstdlib>
#include <filesystem>

#include "core/error.h"
#include "core/log.h"
#include "datasets/data_root.h"
#include "datasets/eth_ucy.h"
#include "datasets/track_store.h"

namespace foresight {
namespace fs = std::filesystem;

std::string ResolveDataPath(const PedestrianDataConfig& c, const std::string& file) {
  return ResolveDataFile(c.root, file);
}

bool DataFilesPresent(const PedestrianDataConfig& c) {
  if (c.format == TrackFormat::kSynthetic) return true;
  for (const auto* list : {&c.train_files, &c.val_files, &c.test_files})
    for (const auto& f : *list)
      if (!fs::exists(ResolveDataPath(c, f))) return false;
  return true;
}

namespace {
TrackSet LoadFiles(const PedestrianDataConfig& c, const std::vector<std::string>& files,
                   const char* role) {
  TrackSet all;
  all.seconds_per_step = c.seconds_per_step;
  for (const auto& file : files) {
    const std::string path = ResolveDataPath(c, file);
    FS_THROW_UNLESS(fs::exists(path), path, ": ", role,
                    " file not found (set data.root or $FORESIGHT_DATA)");
    TrackSet part = c.format == TrackFormat::kEthUcy ? ReadEthUcy(path, c.seconds_per_step)
                                                     : ReadTrackStore(path);
    FS_THROW_UNLESS(std::abs(part.seconds_per_step - c.seconds_per_step) < 1e-9, path,
                    ": sampled every ", part.seconds_per_step, " s but data.seconds_per_step is ",
                    c.seconds_per_step);
    all.source += (all.source.empty() ? "" : ",") + file;
    for (auto& t : part.tracks) all.tracks.push_back(std::move(t));
  }
  return all;
}
}  // namespace

TrackSplit LoadPedestrianSplits(const PedestrianDataConfig& c, std::uint64_t seed) {
  if (c.format == TrackFormat::kSynthetic) {
    TrackSet all = GenerateSyntheticPedestrians(c.synthetic);
    log::Info("synthetic pedestrians: ", all.tracks.size(), " tracks, ", all.NumPoints(),
              " points");
    return SplitTracks(all, c.val_fraction, c.test_fraction, seed);
  }
  FS_THROW_UNLESS(!c.train_files.empty(), "data.train_files is empty for format ",
                  c.format == TrackFormat::kEthUcy ? "eth_ucy" : "track_store");
  TrackSet train = LoadFiles(c, c.train_files, "training");
  const bool split_val = c.val_files.empty(), split_test = c.test_files.empty();
  TrackSplit out;
  if (split_val || split_test) {
    out = SplitTracks(train, split_val ? c.val_fraction : 0.0, split_test ? c.test_fraction : 0.0,
                      seed);
  } else {
    out.train = std::move(train);
  }
  if (!split_val) out.val = LoadFiles(c, c.val_files, "validation");
  if (!split_test) out.test = LoadFiles(c, c.test_files, "test");
  log::Info("tracks: ", out.train.tracks.size(), " train, ", out.val.tracks.size(), " val, ",
            out.test.tracks.size(), " test");
  return out;
}

}  // namespace foresight
