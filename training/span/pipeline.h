#pragma once
/// The SPAN predictor through the one pipeline:
///   data -> windows -> ridge targets -> train (LibTorch) -> export (.h5) -> eval (Eigen engine).
/// Run directory: config.yaml, log.txt, metrics.csv, normalisation.h5, checkpoints/, model.h5,
/// eval.json, plots/samples.png.

#include <string>

#include "training/run_dir.h"
#include "training/span/config.h"
#include "training/trainer.h"

namespace foresight {

/// What shows a SPAN run in a directory: a metrics.csv without checkpoints (a run killed in
/// epoch 1) holds nothing to resume, so a fresh start replaces it.
inline const RunDirectoryRules kSpanRunRules{{"checkpoints/", "model.h5", "eval.json"}, true};

/// Trains (or resumes) into `run_dir`; writes the resolved config and the normalisation first.
/// A fresh start (not `resume`) refuses a directory that already holds checkpoints, metrics.csv,
/// model.h5 or eval.json. No training or validation windows is an Error naming the split keys.
TrainingSummary TrainSpan(const SpanExperimentConfig& config, const std::string& run_dir,
                          bool resume, const TrainHooks& hooks = {});

/// Writes `run_dir`/model.h5 from the best checkpoint. @return the artifact path.
std::string ExportSpan(const std::string& run_dir);

/// Writes the artifact of a SpanNet checkpoint at `checkpoint` (used by export and tests).
void WriteSpanArtifact(const SpanExperimentConfig& config, const std::string& checkpoint,
                       const std::string& normalisation_file, const std::string& artifact_path);

}  // namespace foresight
