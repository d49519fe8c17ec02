#pragma once
/// Occupancy maps that are logistic regressions on hinge features (core/hinge_grid.h):
///   Hilbert map  f(x) = w' phi(x),            p = sigmoid(f)               (point weights)
///   Fast-BHM     w_t ~ N(mu_t, s2_t) independent (mean-field)              (thesis ch 3)
///   BHM          w ~ N(mu, Sigma) with full covariance                     (Senanayake & Ramos
///   2017)
/// Bayesian maps predict with the probit approximation of the logistic-Gaussian integral
/// (Bishop 2006, eq. 4.153):  p = sigmoid(mu_f / sqrt(1 + pi s2_f / 8)),
///   mu_f = mu' phi(x),  s2_f = phi' Sigma phi  (= sum_t phi_t^2 s2_t for Fast-BHM).
/// The occupied class is y = 1 (see spec/errata.md, ch 2).
///
/// Artifact (docs/artifact_schema.md): /model attrs {x_min, x_max, y_min, y_max, spacing, gamma,
/// cutoff_radius, prior_mean, prior_variance}, /weights/mean [T], /weights/variance [T]
/// (Bayesian), /weights/covariance [T x T] (BHM), stored as float32 or float64.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "core/hinge_grid.h"
#include "inference/mapping/occupancy_map.h"

namespace foresight::occupancy {

enum class HingeMapKind { kHilbert, kFastBhm, kBhm };
const char* ModelType(HingeMapKind kind);

/// Weights of a hinge map; shapes must match the grid (checked by HingeMap).
struct HingeWeights {
  Eigen::VectorXd mean;        ///< [T]
  Eigen::VectorXd variance;    ///< [T] marginal variances (Bayesian kinds); empty for Hilbert maps
  Eigen::MatrixXd covariance;  ///< [T x T] full covariance (BHM only), else empty
};

enum class StoredPrecision { kFloat32, kFloat64 };

class HingeMap final : public Map {
 public:
  /// @param prior_mean, prior_variance the weight prior, reported where the map has no features.
  HingeMap(HingeMapKind kind, HingeGrid grid, HingeWeights weights, double prior_mean,
           double prior_variance);
  /// Loads a hinge-map artifact; `expected_type` empty accepts any hinge kind.
  static HingeMap Load(const std::string& path, const std::string& expected_type = "");
  /// Writes a complete artifact (header, resolved config, weights).
  void Save(const std::string& path, const std::string& config_yaml, std::int64_t seed,
            StoredPrecision precision = StoredPrecision::kFloat32) const;

  HingeMapKind kind() const { return kind_; }
  const HingeGrid& grid() const { return grid_; }
  const HingeWeights& weights() const { return weights_; }
  double prior_mean() const { return prior_mean_; }
  double prior_variance() const { return prior_variance_; }

  std::string model_type() const override { return ModelType(kind_); }
  MapWorkspace MakeWorkspace() const override;
  QueryResult Query(double x, double y, MapWorkspace* ws) const override;
  double Probability(double x, double y, MapWorkspace* ws) const override;
  Eigen::Vector4d Extent() const override;

  /// Latent mean and variance of f(x) (no probit squashing). Returns false where (x, y) has no
  /// features (outside the grid, or not finite): mean and variance are then the prior's.
  bool Latent(double x, double y, MapWorkspace* ws, double* mean, double* variance) const;

 private:
  HingeMapKind kind_;
  HingeGrid grid_;
  HingeWeights weights_;
  double prior_mean_, prior_variance_;
};

/// The probit-approximated predictive probability sigmoid(m / sqrt(1 + pi v / 8)).
double PredictiveProbability(double latent_mean, double latent_variance);

}  // namespace foresight::occupancy
