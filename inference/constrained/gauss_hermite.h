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

/// `rule` without its smallest weights, as many as fit in `max_dropped_mass` together (the
/// tensor product's corners and edges: at 1e-6, 202 of 576 points kept at order 24, 271 of 1024
/// at order 32, none dropped at order 4). For any function f in [0, 1] (an occupancy probability)
/// the pruned rule's sum differs from the full rule's by at most the dropped mass, which is at most
/// `max_dropped_mass`; the weights are not renormalised. The kept points stay in the rule's order.
/// max_dropped_mass in [0, 1); Error otherwise.
StandardNormalRule2 PrunedRuleByMass(const StandardNormalRule2& rule, double max_dropped_mass);

}  // namespace foresight::constrained
