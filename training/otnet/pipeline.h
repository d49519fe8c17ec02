#pragma once
/// The OTNet run (thesis ch 6), `foresight train configs/otnet/<name>.yaml`:
///   maps + trajectories -> map-level split -> RBF weights, Hausdorff encoding -> mixture density
///   network (trainer) -> model.h5 (engine) -> eval.json on validation and test maps, plots/.
/// Run directory: config.yaml, log.txt, checkpoints/, metrics.csv, model.h5, eval.json,
/// plots/test_maps.png (and plots/transfer.png). A killed run resumes (--resume).

#include <atomic>
#include <string>

#include "training/otnet/config.h"

namespace foresight::otnet {

/// Trains and exports. @return false when interrupted (resume continues).
bool TrainOtnetRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
                   const std::atomic<bool>* interrupt);
/// Writes run_dir/model.h5 from the best checkpoint. @return its path.
std::string ExportOtnetRun(const std::string& run_dir);
/// Evaluates run_dir/model.h5; writes run_dir/eval.json (and plots). @return its text.
std::string EvaluateOtnetRun(const ExperimentConfig& c, const std::string& run_dir);

}  // namespace foresight::otnet
