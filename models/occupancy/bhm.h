#pragma once
/// Bayesian Hilbert map with a full weight covariance (Senanayake & Ramos 2017), the slow baseline
/// of thesis ch 3. Sequential variational EM in information form, one scan at a time:
///   E-step  P = P0 + 2 Phi' Lambda(z) Phi,  mu = P^-1 (P0 mu0 + Phi' (y - 1/2)),  Sigma = P^-1
///   M-step  z_n^2 = phi_n' Sigma phi_n + (phi_n' mu)^2
/// Every scan factorises the T x T precision (O(T^3)), which is what Fast-BHM avoids; use it on
/// small feature grids only.

#include <Eigen/Core>

#include "models/occupancy/fast_bhm.h"

namespace foresight::occupancy {

class BhmLearner {
 public:
  /// Shares FastBhmConfig (prior, EM iterations, bound initialisation). T above 4096 is refused.
  BhmLearner(HingeGrid grid, const FastBhmConfig& config);
  void Update(const Eigen::Ref<const Eigen::Matrix2Xd>& xy, const std::uint8_t* occupied);
  const Eigen::VectorXd& mean() const { return mean_; }
  const Eigen::MatrixXd& covariance() const { return covariance_; }
  HingeMap ToMap() const;

 private:
  void Bounds();
  HingeGrid grid_;
  FastBhmConfig config_;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd covariance_, precision_;
  SparseFeatures features_;
  std::vector<double> z_;
};

}  // namespace foresight::occupancy
