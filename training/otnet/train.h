#pragma once
/// Trains OTNet's mixture density network with the trainer and exports the engine artifact.

#include <atomic>
#include <string>

#include "training/otnet/config.h"
#include "training/otnet/data.h"

namespace foresight::otnet {

/// Everything training and export need, computed deterministically from the config.
struct OtnetPrepared {
  OtnetData data;
  TrajectoryBasis basis;
  MapEncoder encoder;
  EncodedSplit train, val;
};
OtnetPrepared PrepareOtnet(const ExperimentConfig& c);

/// Trains in run_dir (checkpoints/, metrics.csv). @return false when interrupted.
bool TrainOtnet(const ExperimentConfig& c, const OtnetPrepared& p, const std::string& run_dir,
                bool resume, const std::atomic<bool>* interrupt);
/// Writes run_dir/model.h5 from the best checkpoint. @return its path.
std::string ExportOtnet(const ExperimentConfig& c, const OtnetPrepared& p,
                        const std::string& run_dir);

}  // namespace foresight::otnet
