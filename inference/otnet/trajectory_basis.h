#pragma once
/// OTNet's trajectory representation (thesis ch 6, "Learning a Mixture of Stochastic Processes"):
/// x(tau) = w_x' k(tau), y(tau) = w_y' k(tau) on normalised time tau in [0, 1], with M Gaussian
/// RBFs k_j(tau) = exp(-gamma (tau - c_j)^2) at evenly spaced centres c_j on [0, 1] (errata: the
/// Gaussian RBF). A trajectory of n waypoints is given the times tau_i = i / (n - 1) and its
/// weights are the ridge fit shared with SPAN (core/rbf.h, TimeBasis::FitRidge), so trajectories of
/// any length map to the same w = [w_x; w_y] in R^{2M}.

#include <Eigen/Core>

#include "core/rbf.h"

namespace foresight::otnet {

class TrajectoryBasis {
 public:
  TrajectoryBasis() = default;
  /// @param num_basis M >= 2. @param gamma > 0. @param ridge lambda >= 0. Error otherwise.
  TrajectoryBasis(int num_basis, double gamma, double ridge);

  int size() const { return basis_.size(); }  ///< M
  int weights() const { return 2 * size(); }  ///< 2M
  double gamma() const { return basis_.gamma(); }
  double ridge() const { return ridge_; }
  const TimeBasis& time_basis() const { return basis_; }

  /// w = [w_x; w_y] [2M] for waypoints [n x 2] (n >= 2; Error otherwise or on non-finite values).
  Eigen::VectorXd Fit(const Eigen::MatrixX2d& waypoints) const;
  /// K(taus) [L x M], row l = k(tau_l)'.
  Eigen::MatrixXd Design(const Eigen::VectorXd& taus) const;
  /// Positions [L x 2] of weights w [2M] at taus [L].
  Eigen::MatrixX2d Evaluate(const Eigen::VectorXd& w, const Eigen::VectorXd& taus) const;

 private:
  TimeBasis basis_;
  double ridge_ = 0;
};

/// L uniform times 0, 1/(L-1), ..., 1 (L >= 2).
Eigen::VectorXd UniformTaus(int count);

}  // namespace foresight::otnet
