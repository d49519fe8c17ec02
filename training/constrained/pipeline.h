#pragma once
/// The constrained-prediction run (thesis ch 7), `foresight train configs/constrained/<name>.yaml`:
///   scenes (tracks + obstacle raster) -> split -> windows -> prior (mixture of matrix normals),
///   KTM and naive networks (trainer) -> prior.h5, ktm.h5, naive.h5 (engines) -> maps/<scene>.h5
///   (occupancy map per test scene) -> eval.json (prior vs optimised vs baselines), tracks.csv,
///   plots/window_<k>.png.
/// Run directory: config.yaml, log.txt, prior/, ktm/, naive/ (each: checkpoints/, metrics.csv,
/// normalisation.h5), the artifacts, maps/, eval.json. A killed run resumes (--resume): a learner
/// whose artifact exists is skipped, the one in progress continues from its last checkpoint.

#include <atomic>
#include <string>

#include "training/constrained/config.h"

namespace foresight::constrained {

/// Trains every learner, exports the artifacts and fits the test scenes' maps. @return false when
/// interrupted (resume continues).
bool TrainConstrainedRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
                         const std::atomic<bool>* interrupt);
/// Writes the run's artifacts (prior.h5, ktm.h5, naive.h5) from each learner's best checkpoint.
/// @return the prior's path.
std::string ExportConstrainedRun(const std::string& run_dir);
/// Evaluates the run's artifacts with `c` (the run's config, overrides applied); writes eval.json.
std::string EvaluateConstrainedRun(const ExperimentConfig& c, const std::string& run_dir);

}  // namespace foresight::constrained
