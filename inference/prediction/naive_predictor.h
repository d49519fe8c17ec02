#pragma once
/// LibTorch-free engine of the naive network baseline of structurally constrained prediction
/// (thesis ch 7, "NN-naive"): a ReLU MLP (560 -> 180 -> 180) maps the normalised ego-frame past
/// [2p] directly to the ego-frame future [2f], trained by mean squared error. A point prediction
/// (no distribution).
///
///   NaivePredictor model = NaivePredictor::Load("naive.h5");  // immutable, share across threads
///   auto ws = model.MakeWorkspace();                           // one per caller
///   model.Predict(past, &ws, future);                          // no allocation

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "inference/engine/dense.h"

namespace foresight {

inline constexpr const char* kNaiveModelType = "naive_predictor";

/// Everything a naive_predictor artifact holds besides its header (docs/artifact_schema.md):
///   /model attrs observed, predicted, seconds_per_step, rotate_to_heading, dense_layers
///   /normalisation/input_mean, input_std [2p]; /weights/<layer>/{weight,bias} (float)
struct NaivePredictorWeights {
  int observed = 0, predicted = 0;        ///< points observed / predicted per window
  double seconds_per_step = 0;            ///< s between points
  bool rotate_to_heading = true;          ///< ego frame rotated to the observed heading
  Eigen::VectorXd input_mean, input_std;  ///< [2 observed] of the ego-frame past
  std::vector<std::string> layer_names;   ///< dense layers in order ("mlp.0", ..., "head")
  Mlp mlp;                                ///< [2p] -> [2f] ego-frame future x_1, y_1, ...
};

class NaivePredictor {
 public:
  struct Workspace {
    Eigen::VectorXf input;  ///< [2p] normalised ego-frame past
    Mlp::Workspace mlp;
  };

  /// Loads an artifact of model_type "naive_predictor"; inconsistent files are an Error naming
  /// the file and the values.
  static NaivePredictor Load(const std::string& path);
  /// Writes an artifact that Load reads (to path.tmp, then renamed into place).
  static void Save(const std::string& path, const NaivePredictorWeights& weights,
                   const std::string& config_yaml, std::int64_t seed);

  int observed() const { return observed_; }
  int predicted() const { return predicted_; }
  double seconds_per_step() const { return seconds_per_step_; }
  const Mlp& mlp() const { return mlp_; }

  Workspace MakeWorkspace() const;

  /// @param past [p x 2] observed positions (world, m), oldest first, one every seconds_per_step.
  /// @param future [f x 2] predicted positions (world, m) at 1..f steps after the last observed.
  /// No allocation. Wrong shapes or non-finite input are an Error (checked before any work).
  void Predict(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 2>>& past,
               Workspace* ws, Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 2>> future) const;

 private:
  int observed_ = 0, predicted_ = 0;
  double seconds_per_step_ = 0.4;
  bool rotate_ = true;
  Eigen::VectorXd input_mean_, input_std_;
  Mlp mlp_;
};

}  // namespace foresight
