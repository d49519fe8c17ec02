#pragma once
/// Where pedestrian tracks come from, as configured: real files (ETH/UCY text or the HDF5 track
/// store) or the synthetic generator; and how they split into train / val / test.
///
/// Real files are listed explicitly (any scene in the format works); the leave-one-out protocol
/// of ../shared/data/eth_ucy/README.md is a choice of lists (configs/span/eth_ucy_*.yaml).
/// When val_files / test_files are empty, tracks of train_files are split by a seeded shuffle.

#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/synthetic_pedestrians.h"
#include "datasets/windows.h"

namespace foresight {

enum class TrackFormat { kSynthetic, kEthUcy, kTrackStore };

struct PedestrianDataConfig {
  TrackFormat format = TrackFormat::kSynthetic;
  /// Relative file names are resolved against this directory. Empty: $FORESIGHT_DATA, else
  /// ../shared/data relative to the working directory.
  std::string root;
  std::vector<std::string> train_files, val_files, test_files;
  double seconds_per_step = 0.4;  ///< one frame step of the files (s)
  double val_fraction = 0.1;      ///< used when val_files is empty
  double test_fraction = 0.1;     ///< used when test_files is empty
  SyntheticPedestrianConfig synthetic;

  template <class A>
  void Serialize(A* a) {
    a->VisitEnum("format", &format,
                 config::EnumNames<TrackFormat>{{TrackFormat::kSynthetic, "synthetic"},
                                                {TrackFormat::kEthUcy, "eth_ucy"},
                                                {TrackFormat::kTrackStore, "track_store"}},
                 "source of the tracks");
    a->Visit("root", &root, config::Range::Any(),
             "directory for relative file names (empty: $FORESIGHT_DATA or ../shared/data)");
    a->Visit("train_files", &train_files, config::Range::Any(), "training files");
    a->Visit("val_files", &val_files, config::Range::Any(),
             "validation files (empty: split from train_files)");
    a->Visit("test_files", &test_files, config::Range::Any(),
             "test files (empty: split from train_files)");
    a->Visit("seconds_per_step", &seconds_per_step, config::Range::Positive(),
             "seconds per frame step of the files");
    a->Visit("val_fraction", &val_fraction, config::Range::Closed(0, 0.9),
             "fraction of tracks held out for validation when val_files is empty");
    a->Visit("test_fraction", &test_fraction, config::Range::Closed(0, 0.9),
             "fraction of tracks held out for testing when test_files is empty");
    a->Visit("synthetic", &synthetic, config::Range::Any(),
             "synthetic generator (format: synthetic)");
  }
};

/// Sampling step of the configured tracks (s).
inline double SecondsPerStep(const PedestrianDataConfig& c) {
  return c.format == TrackFormat::kSynthetic ? c.synthetic.seconds_per_step : c.seconds_per_step;
}

/// Resolves `file` against the data root (see PedestrianDataConfig::root).
std::string ResolveDataPath(const PedestrianDataConfig& config, const std::string& file);
/// True when every configured real file exists (tests skip otherwise).
bool DataFilesPresent(const PedestrianDataConfig& config);

/// Loads and splits the tracks; deterministic in the config and `seed`.
TrackSplit LoadPedestrianSplits(const PedestrianDataConfig& config, std::uint64_t seed);

}  // namespace foresight
