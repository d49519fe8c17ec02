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

/// `rule` without the points whose weight is below `min_weight` (the tensor product's corners:
/// at 1e-12, none below order 11 and 124 of 400 at order 20). The dropped mass, at most n^2
/// min_weight, bounds the change of any expectation of a function in [0, 1] (such as an occupancy
/// probability); the weights are not renormalised. min_weight in [0, 1); Error otherwise.
StandardNormalRule2 PrunedRule(const StandardNormalRule2& rule, double min_weight);

}  // namespace foresight::constrained
