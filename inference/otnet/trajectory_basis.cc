#include "inference/otnet/trajectory_basis.h"

#include <cmath>

#include "core/error.h"

namespace foresight::otnet {

TrajectoryBasis::TrajectoryBasis(int num_basis, double gamma, double ridge) : ridge_(ridge) {
  FS_THROW_UNLESS(num_basis >= 2, "TrajectoryBasis: num_basis M must be >= 2, got ", num_basis);
  FS_THROW_UNLESS(gamma > 0 && std::isfinite(gamma),
                  "TrajectoryBasis: gamma must be > 0 and finite, got ", gamma);
  FS_THROW_UNLESS(ridge >= 0 && std::isfinite(ridge),
                  "TrajectoryBasis: ridge must be >= 0 and finite, got ", ridge);
  // M Gaussian RBFs at evenly spaced centres on tau in [0, 1] (thesis ch 6; errata: Gaussian RBF).
  basis_ = TimeBasis(num_basis, 0.0, 1.0, gamma);
}

Eigen::VectorXd TrajectoryBasis::Fit(const Eigen::MatrixX2d& waypoints) const {
  FS_THROW_UNLESS(size() >= 2, "TrajectoryBasis::Fit: the basis is not initialised");
  const int n = static_cast<int>(waypoints.rows());
  FS_THROW_UNLESS(n >= 2, "TrajectoryBasis::Fit: need at least 2 waypoints, got ", n);
  for (int i = 0; i < n; ++i)
    FS_THROW_UNLESS(waypoints.row(i).allFinite(), "TrajectoryBasis::Fit: waypoint ", i, " (",
                    waypoints(i, 0), ", ", waypoints(i, 1), ") is not finite");
  // Waypoint i sits at tau_i = i / (n - 1); the ridge fit gives W [M x 2] = [w_x, w_y].
  const Eigen::MatrixXd w = basis_.FitRidge(UniformTaus(n), waypoints, ridge_);
  Eigen::VectorXd out(weights());
  out.head(size()) = w.col(0);
  out.tail(size()) = w.col(1);
  return out;
}

Eigen::MatrixXd TrajectoryBasis::Design(const Eigen::VectorXd& taus) const {
  FS_THROW_UNLESS(size() >= 2, "TrajectoryBasis::Design: the basis is not initialised");
  return basis_.Design(taus);
}

Eigen::MatrixX2d TrajectoryBasis::Evaluate(const Eigen::VectorXd& w,
                                           const Eigen::VectorXd& taus) const {
  FS_THROW_UNLESS(size() >= 2, "TrajectoryBasis::Evaluate: the basis is not initialised");
  FS_THROW_UNLESS(w.size() == weights(), "TrajectoryBasis::Evaluate: w has ", w.size(),
                  " entries, expected 2M = ", weights());
  // x(tau) = w_x' k(tau), y(tau) = w_y' k(tau) (thesis ch 6).
  const Eigen::MatrixXd k = basis_.Design(taus);
  Eigen::MatrixX2d out(taus.size(), 2);
  out.col(0) = k * w.head(size());
  out.col(1) = k * w.tail(size());
  return out;
}

Eigen::VectorXd UniformTaus(int count) {
  FS_THROW_UNLESS(count >= 2, "UniformTaus: count must be >= 2, got ", count);
  Eigen::VectorXd taus(count);
  // i / (count - 1) exactly, so the ends are 0 and 1.
  for (int i = 0; i < count; ++i) taus[i] = static_cast<double>(i) / (count - 1);
  return taus;
}

}  // namespace foresight::otnet
