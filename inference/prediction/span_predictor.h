#pragma once
/// LibTorch-free engine of the SPAN pedestrian predictor (thesis ch 5; mixture head of ch 7).
///
///   Predictor model = Predictor::Load("model.h5");   // immutable, share across
///   threads auto ws = model.MakeWorkspace();                           // one per caller auto out
///   = model.MakeDistribution();                        // preallocated output model.Predict(past,
///   &ws, &out);                             // no allocation out.Position(t, &mean, &cov); // o(t)
///   ~ N(M' phi, (phi' U phi) V)

#include <Eigen/Core>
#include <random>
#include <string>
#include <vector>

#include "core/matrix_normal.h"
#include "core/matrix_normal_head.h"
#include "core/rbf.h"
#include "inference/engine/dense.h"
#include "inference/prediction/trajectory_distribution.h"

namespace foresight::span {

inline constexpr const char* kModelType = "span_predictor";

/// Everything a span_predictor artifact holds besides its header: the engine's schema, written by
/// Predictor::Save and read by Predictor::Load (docs/artifact_schema.md).
struct PredictorWeights {
  int observed = 0, predicted = 0;  ///< points observed / predicted per window
  double seconds_per_step = 0;      ///< s between points
  bool rotate_to_heading = true, residual_to_constant_velocity = false;
  HeadLayout layout;
  Eigen::VectorXd basis_centres;  ///< [basis] s
  double basis_gamma = 0;
  Eigen::VectorXd input_mean, input_std;  ///< [2 observed]
  std::vector<std::string>
      layer_names;  ///< module paths of the dense layers ("mlp.0", ..., "head")
  Mlp mlp;
  /// Optional KTM input stage (Kernel Trajectory Maps, thesis ch 7 baseline): the net's inputs are
  /// k(q, r_i) = exp(-d(q, r_i)^2 / (2 l^2)), d = RMS pointwise distance between the ego-frame
  /// past q and reference r_i; input_mean/std then have K entries.
  Eigen::MatrixXd ktm_references;  ///< [K x 2p] ego frame (m); empty: raw input
  double ktm_lengthscale = 0;      ///< l (m); used when ktm_references is not empty
  /// c: every predicted covariance is c (phi' U phi) V, i.e. V is scaled by c; fitted on
  /// validation windows when the config asks for it (training/span/calibration.h), else 1.
  double covariance_scale = 1.0;
};

class Predictor {
 public:
  struct Workspace {
    Eigen::VectorXf input;
    Mlp::Workspace mlp;
    Eigen::VectorXd raw;
    Eigen::Matrix<double, Eigen::Dynamic, 2> past;  ///< batch row unpacked as [p x 2]
    Eigen::VectorXd ego;  ///< [2p] ego-frame past (input of the KTM stage)
  };

  /// Loads an artifact written by `foresight export` (model_type "span_predictor").
  static Predictor Load(const std::string& path);
  /// Writes an artifact that Load reads (to path.tmp, then renamed into place).
  static void Save(const std::string& path, const PredictorWeights& weights,
                   const std::string& config_yaml, std::int64_t seed);

  int observed() const { return observed_; }
  double seconds_per_step() const { return seconds_per_step_; }
  const HeadLayout& layout() const { return layout_; }
  const TimeBasis& basis() const { return basis_; }
  const Mlp& mlp() const { return mlp_; }
  /// KTM references [K x 2p] (ego frame, m); empty when the net reads the past directly.
  const Eigen::MatrixXd& ktm_references() const { return ktm_references_; }
  double ktm_lengthscale() const { return ktm_lengthscale_; }
  /// c of PredictorWeights::covariance_scale (1 in artifacts written without one).
  double covariance_scale() const { return covariance_scale_; }

  Workspace MakeWorkspace() const;
  TrajectoryDistribution MakeDistribution() const;

  /// @param past [p x 2] observed positions (world, m), oldest first, one every seconds_per_step.
  /// Non-finite input is an Error (checked before any work).
  void Predict(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 2>>& past,
               Workspace* ws, TrajectoryDistribution* out) const;
  /// Batch form: row k of `past_rows` is x_1, y_1, ..., x_p, y_p. `out` must hold N distributions.
  void PredictBatch(const Eigen::Ref<const Eigen::MatrixXd>& past_rows, Workspace* ws,
                    std::vector<TrajectoryDistribution>* out) const;
  /// Raw head outputs (before activations) for the normalised input of `past`: parity tests.
  /// Leaves the normalised net input (2p ego points, or K KTM features) in ws->input.
  void RawOutput(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 2>>& past,
                 Workspace* ws) const;

 private:
  int observed_ = 0;
  double seconds_per_step_ = 0.4;
  bool rotate_ = true;
  bool residual_cv_ = false;
  HeadLayout layout_;
  TimeBasis basis_;
  Eigen::VectorXd input_mean_, input_std_;
  Mlp mlp_;
  Eigen::MatrixXd ktm_references_;
  double ktm_lengthscale_ = 0;
  double covariance_scale_ = 1.0;
};

}  // namespace foresight::span
