#pragma once
/// Chance-constrained collision of the robot (a point x with radius r_x) with a pedestrian whose
/// position is Gaussian, o ~ N(mu, Sigma) (thesis ch 5, eq. upperbounds; Zhu and Alonso-Mora 2019;
/// spec/errata.md: printed correctly):
///   P(||x - o|| < r) <= 1/2 [1 + erf((r - a'd) / sqrt(2 a' Sigma a))],  d = x - mu,  a = d /
///   ||d||,
/// with r = r_x + r_o. A collision at time t is declared when the bound exceeds epsilon (eq.
/// dynamicCheck). Because erf is increasing, "bound > epsilon" is the same test as
///   ||d|| < r + c_eps sqrt(2 a' Sigma a),   c_eps = -erfinv(2 epsilon - 1),
/// which the controller's inner loop uses (no erf per pedestrian and step).

#include <Eigen/Core>

namespace foresight::nav {

/// The erf upper bound on P(||x - o|| < radius) for o ~ N(mean, cov). At d = 0 the direction a is
/// undefined and the bound is 1 (the point is inside the disc around the mean).
double CollisionProbabilityBound(const Eigen::Vector2d& x, const Eigen::Vector2d& mean,
                                 const Eigen::Matrix2d& cov, double radius);

/// Inverse error function on (-1, 1) (Giles 2010 initial guess refined by two Newton steps; |error|
/// < 1e-12).
double ErfInv(double y);

/// The threshold test "bound > epsilon" in its erf-free form (see above), for one epsilon.
class ChanceThreshold {
 public:
  /// @param epsilon in (0, 1).
  explicit ChanceThreshold(double epsilon);
  double epsilon() const { return epsilon_; }
  double c() const { return c_; }
  /// True when the bound for a point at offset d = x - mean from the pedestrian mean exceeds
  /// epsilon.
  bool Exceeds(const Eigen::Vector2d& d, const Eigen::Matrix2d& cov, double radius) const;

 private:
  double epsilon_, c_;
};

}  // namespace foresight::nav
