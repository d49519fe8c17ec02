#pragma once
/// Gauss-Hermite quadrature (thesis ch 7, "Obstacle cost operator"; errata: change of variables
/// through the Cholesky factor). The n-point rule integrates exp(-x^2) p(x) exactly for polynomials
/// p of degree <= 2n - 1; nodes and weights by Golub-Welsch (eigen-decomposition of the Jacobi
/// matrix of the Hermite polynomials).

#include <Eigen/Core>

namespace foresight::constrained {

/// int exp(-x^2) f(x) dx ~ sum_i weights_i f(nodes_i) (physicists' convention).
struct GaussHermiteRule {
  Eigen::VectorXd nodes;    ///< [n], ascending
  Eigen::VectorXd weights;  ///< [n], positive, sum sqrt(pi)
};
/// n in [1, 64]; Error otherwise.
GaussHermiteRule GaussHermite(int n);

/// E_{z ~ N(0, I_2)}[f(z)] ~ sum_k weights_k f(points_k): the tensor product of the order-n rule
/// after z = sqrt(2) x, so points are sqrt(2) (x_i, x_j) and weights w_i w_j / pi (sum 1).
struct StandardNormalRule2 {
  Eigen::Matrix2Xd points;  ///< [2 x n^2]
  Eigen::VectorXd weights;  ///< [n^2]
  int size() const { return static_cast<int>(weights.size()); }
};
StandardNormalRule2 StandardNormalRule(int order);

/// StandardNormalRule(order) without its lightest points, as many as fit in `max_dropped_mass`
/// together, dropped in whole orbits of the square's symmetries (mirror in either axis, swap of
/// the axes), so the kept rule stays symmetric: zero mean and isotropic covariance, to rounding.
/// For any function f in [0, 1] (an occupancy probability) the pruned rule's sum differs from the
/// full rule's by at most the dropped mass (<= max_dropped_mass); the weights are not renormalised,
/// and the kept points stay in the rule's order. Nothing is dropped at order 4 at 1e-6; most of
/// the tensor product's corners and edges at high orders. order in [1, 64], max_dropped_mass in
/// [0, 1); Error otherwise.
StandardNormalRule2 PrunedRuleByMass(int order, double max_dropped_mass);

}  // namespace foresight::constrained
