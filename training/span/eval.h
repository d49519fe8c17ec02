#pragma once
/// Evaluation of an exported SPAN predictor artifact with the Eigen engine, against a
/// constant-velocity baseline with a Gaussian fitted per horizon on the training windows.

#include <string>
#include <vector>

#include "datasets/windows.h"
#include "training/span/config.h"

namespace foresight::span {

struct Metrics {
  double ade = 0, fde = 0;  ///< of the mean prediction (m)
  double nll = 0;           ///< -log density per future point (positions, nats)
  double best_of_n_ade = 0, best_of_n_fde = 0;
  /// Calibration, per future step: the share of windows whose true position lies inside the 1-
  /// and 2-sigma ellipses of the predicted position's Gaussian (the mixture's moments); nominal
  /// 39.3 % and 86.5 % in 2-D. Below nominal: overconfident; above: too broad.
  std::vector<double> within_1sigma, within_2sigma;
};

struct EvalReport {
  int windows = 0;
  double covariance_scale = 1.0;  ///< of the evaluated artifact (1: not calibrated)
  std::vector<double> horizon_s;  ///< time of each future step after the last observed point (s)
  Metrics model, cv;
  /// The same metrics on the validation windows (for choosing hyper-parameters; never the test).
  int val_windows = 0;
  Metrics val_model, val_cv;
  /// Valid JSON: non-finite metrics are null, and so is "val" without validation windows.
  std::string ToJson(int num_samples) const;
};

/// Evaluates `artifact` on the test windows of `config`; writes `out_dir`/eval.json and
/// `out_dir`/plots/samples.png. The data, windows and seed sections of `config` must be those the
/// artifact was trained with (its /config; data.root may differ), else an Error names the first
/// differing key. No test or training windows is an Error naming the keys that control the split.
EvalReport Evaluate(const ExperimentConfig& config, const std::string& artifact,
                    const std::string& out_dir);

/// Same on given windows, the CV Gaussian fitted on `train` (no files written); empty `train` or
/// `test` is an Error.
EvalReport EvaluateOn(const std::string& artifact, const WindowSet& train, const WindowSet& test,
                      const EvalConfig& eval);

}  // namespace foresight::span
