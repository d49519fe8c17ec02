#pragma once
/// The SPAN predictor through the one pipeline:
///   data -> windows -> ridge targets -> train (LibTorch) -> export (.h5) -> eval (Eigen engine).
/// Run directory: config.yaml, log.txt, metrics.csv, normalisation.h5, checkpoints/, model.h5,
/// eval.json, plots/samples.png.
///
/// The pieces below TrainSpan (TrainSpanOnWindows, TrainSpanNet, SpanWeightsFromCheckpoint) train
/// and export the same net from given windows or given input features; the learners of
/// constrained prediction (training/constrained/learners.h) use them.

#include <cstdint>
#include <string>
#include <vector>

#include "inference/engine/dense.h"
#include "inference/prediction/span_predictor.h"
#include "models/span/span_config.h"
#include "models/span/span_data.h"
#include "training/run_dir.h"
#include "training/span/config.h"
#include "training/trainer.h"

namespace foresight::span {

/// What shows a SPAN run in a directory: a metrics.csv without checkpoints (a run killed in
/// epoch 1) holds nothing to resume, so a fresh start replaces it.
inline const RunDirectoryRules kRunRules{{"checkpoints/", "model.h5", "eval.json"}, true};

/// Trains (or resumes) into `run_dir`; writes the resolved config and the normalisation first.
/// A fresh start (not `resume`) refuses a directory that already holds checkpoints, metrics.csv,
/// model.h5 or eval.json. No training or validation windows is an Error naming the split keys.
TrainingSummary TrainRun(const ExperimentConfig& config, const std::string& run_dir, bool resume,
                         const TrainHooks& hooks = {});

/// Writes `run_dir`/model.h5 from the best checkpoint; with calibrate_covariance, then fits its
/// covariance scale on the validation windows (training/span/calibration.h). @return the path.
std::string ExportRun(const std::string& run_dir);

// ---------------------------------------------------------------- shared pieces

/// Everything that fixes a SPAN net and its engine besides its weights.
struct ModelSpec {
  int observed = 0, predicted = 0;  ///< points per window
  double seconds_per_step = 0.4;    ///< s between points
  TrajectoryBasisConfig basis;
  NetConfig network;
};

/// The spec of a SPAN experiment (windows, data step, basis, network).
ModelSpec ModelSpecOf(const ExperimentConfig& config);
/// The head layout of `spec` (basis size, R, u_param).
HeadLayout LayoutOf(const ModelSpec& spec);
/// Ego-frame inputs [N x 2p] and ridge targets [N x 2m] of `windows` (models/span/span_data.h).
Samples MakeSamples(const ModelSpec& spec, const WindowSet& windows);

/// Per-feature input normalisation x' = (x - mean) / std, fitted on the training inputs.
struct InputNormalisation {
  Eigen::VectorXd mean, std;  ///< [D]
  Eigen::MatrixXd Apply(const Eigen::MatrixXd& x) const;
};
/// Mean and std per column of `x` [N x D]; constant columns get std 1, others at least 0.01.
InputNormalisation FitInputNormalisation(const Eigen::MatrixXd& x);
/// `path` holds /input_mean and /input_std (written atomically).
void WriteInputNormalisation(const std::string& path, const InputNormalisation& n);
InputNormalisation ReadInputNormalisation(const std::string& path);

/// Trains the SPAN net (SpanNet + mixture NLL of the ridge targets) on given samples into
/// `run_dir` (checkpoints/, metrics.csv, normalisation.h5 of the training inputs). The inputs
/// are any features [N x D] (D = 2p ego-frame points, or KTM features); targets [N x 2m].
/// A fresh start fits and writes the normalisation; `resume` reads it back and continues from
/// the last checkpoint. No training or validation samples is an Error.
TrainingSummary TrainNet(const ModelSpec& spec, const Samples& train, const Samples& val,
                         const TrainConfig& train_config, std::int64_t seed,
                         const std::string& run_dir, bool resume, const TrainHooks& hooks = {});

/// MakeSamples of both window sets, the training ones augmented by `augment` (Augment in
/// models/span/span_data.h), then TrainNet. No windows is an Error.
TrainingSummary TrainOnWindows(const ModelSpec& spec, const WindowSet& train, const WindowSet& val,
                               const TrainConfig& train_config, std::int64_t seed,
                               const std::string& run_dir, bool resume,
                               const TrainHooks& hooks = {}, const AugmentConfig& augment = {});

/// The engine weights of a SpanNet checkpoint with `input_dim` inputs and the normalisation of
/// `normalisation_file`; the caller adds an input stage (KTM) if any and saves them.
PredictorWeights WeightsFromCheckpoint(const ModelSpec& spec, int input_dim,
                                       const std::string& checkpoint,
                                       const std::string& normalisation_file);

/// The engine's dense layers from the module's `names[i].weight` / `.bias` parameters (float).
Mlp ToEngineMlp(torch::nn::Module& net, const std::vector<std::string>& names);

/// A [N x D] double matrix as a float tensor [N, D].
torch::Tensor ToFloatTensor(const Eigen::MatrixXd& m);

}  // namespace foresight::span
