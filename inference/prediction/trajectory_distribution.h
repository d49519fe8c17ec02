#pragma once
/// The output of every trajectory predictor: a mixture of matrix normals over the weights of future
/// trajectories in an RBF time basis, in the world frame (SPAN, ch 5; the constrained prediction
/// of ch 7 projects it; navigation forecasts with it).

#include <Eigen/Core>
#include <random>
#include <vector>

#include "core/matrix_normal.h"
#include "core/rbf.h"

namespace foresight {

namespace span {
class Predictor;
}  // namespace span

/// A predicted mixture of matrix normals over future trajectory weights, in the world frame.
/// Trajectories: o(t) = origin + v t + W' phi(t), t (s) from the last observed point; v is the
/// constant-velocity offset of models trained with residual_to_constant_velocity (else zero).
class TrajectoryDistribution {
 public:
  TrajectoryDistribution() = default;
  TrajectoryDistribution(const TimeBasis& basis, int components);

  int components() const { return static_cast<int>(alpha_.size()); }
  int basis_size() const { return basis_.size(); }
  const Eigen::Vector2d& origin() const { return origin_; }
  const Eigen::Vector2d& velocity() const { return velocity_; }
  double alpha(int r) const { return alpha_[r]; }
  const Eigen::MatrixXd& mean(int r) const { return mean_[static_cast<std::size_t>(r)]; }
  const Eigen::MatrixXd& chol_u(int r) const { return chol_u_[static_cast<std::size_t>(r)]; }
  const Eigen::Matrix2d& chol_v(int r) const { return chol_v_[static_cast<std::size_t>(r)]; }
  /// Component r as a core::MatrixNormal over W (allocates; for tests and tools).
  MatrixNormal Component(int r) const;

  /// Mean [2] and covariance [2 x 2] of component r's position at time t (world, m).
  void Position(double t, int r, Eigen::Vector2d* mean, Eigen::Matrix2d* cov) const;
  /// Mixture mean position at time t (world, m).
  Eigen::Vector2d MeanPosition(double t) const;
  /// Mean [2] and covariance [2 x 2] of the mixture's position at time t (world, m): the moments
  /// of the mixture, sum_r alpha_r (Sigma_r + mu_r mu_r') - mu mu' (exact for one component).
  void MixturePosition(double t, Eigen::Vector2d* mean, Eigen::Matrix2d* cov) const;
  /// log density of the observed position x at time t under the mixture.
  double LogDensity(double t, const Eigen::Vector2d& x) const;
  /// Samples one trajectory at `times` [T] into `path` [T x 2] (preallocated; no allocation).
  void SamplePath(const Eigen::Ref<const Eigen::VectorXd>& times, std::mt19937_64* rng,
                  Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 2>> path) const;

  // Setters for runtimes that rewrite a predicted distribution (the constraint projection of
  // inference/constrained) and for tests that build one by hand. They copy into the preallocated
  // storage: no allocation when the shapes match.
  /// Component r: mean M [m x 2], L_U [m x m] (lower), L_V [2 x 2] (lower). Error naming the sizes
  /// when r is out of range or a shape differs from the distribution's.
  void SetComponent(int r, const Eigen::MatrixXd& mean, const Eigen::MatrixXd& chol_u,
                    const Eigen::Matrix2d& chol_v);
  /// origin [2] (m) and velocity [2] (m/s) of o(t) = origin + v t + W' phi(t), and the mixture
  /// weights alpha [R]. Error when alpha's length is not R.
  void SetFrame(const Eigen::Vector2d& origin, const Eigen::Vector2d& velocity,
                const Eigen::VectorXd& alpha);

 private:
  friend class span::Predictor;  // fills the output without copies
  TimeBasis basis_;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_ = Eigen::Vector2d::Zero();
  Eigen::VectorXd alpha_;
  std::vector<Eigen::MatrixXd> mean_, chol_u_;
  std::vector<Eigen::Matrix2d> chol_v_;
  // Scratch for queries (the distribution is owned by one caller).
  mutable Eigen::VectorXd phi_, u_phi_;
  mutable Eigen::MatrixXd z_, w_;
};

}  // namespace foresight
