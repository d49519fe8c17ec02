#pragma once
/// The diffeomorphic-templates run (thesis ch 8), `foresight train configs/diffeo/<name>.yaml`:
/// for every shape (or task) of the config, the imitation transform is trained by the trainer
/// through its Euler integration (and the Euclideanizing-Flows baseline the same way), exported to
/// models/<shape>.h5 (and models/<shape>.eflow.h5), and evaluated with the torch-free engines.
///
/// Run directory: config.yaml, log.txt; shapes/<shape>/{flow,eflow}/ (the trainer's checkpoints
/// and metrics.csv); models/; eval.json; plots/<shape>.png. A killed run resumes (--resume) from
/// the last checkpoint of the shape it was training; finished shapes are not trained again.

#include <atomic>
#include <string>

#include "training/diffeo/config.h"

namespace foresight::imitation {

/// Trains and exports every shape. @return false when interrupted (resume continues).
bool TrainRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
              const std::atomic<bool>* interrupt);
/// Writes every shape's artifacts from its best checkpoints (run_dir/models/). @return the first
/// shape's template (the only one for single-shape runs).
std::string ExportRun(const std::string& run_dir);
/// Evaluates the run's artifacts; writes run_dir/eval.json (and plots). @return its text.
std::string EvaluateRun(const ExperimentConfig& c, const std::string& run_dir);

}  // namespace foresight::imitation
