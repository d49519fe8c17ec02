#pragma once
/// Fits the occupancy field of a new obstacle (thesis ch 8, "Building Infinitesimal Generators for
/// Collision Avoidance"): a Hilbert map p(o = 1 | s) = sigmoid(w' phi(s) + b) on the RBF grid
/// features (inference/imitation/occupancy_field.h) by L2-penalised logistic regression,
///   min_{w, b}  sum_i [log(1 + exp(f_i)) - y_i f_i] + (l2 / 2) ||w||^2,   f_i = w' phi(s_i) + b,
/// with the bias unpenalised, by Newton's method (IRLS) with a backtracking line search:
///   g = Phi' (p - y) + l2 w,  H = Phi' diag(p (1 - p)) Phi + l2 I  (bias row/column unpenalised).
/// Only the inducing states some sample touches enter the system (the others' weights are 0 at the
/// optimum); H is dense [m_active + 1]^2, solved by LDLT: fine up to a few thousand features.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "inference/imitation/occupancy_field.h"

namespace foresight::imitation {

/// @param points [D x n] sample locations; @param occupied [n] labels (non-zero = occupied).
/// @param l2 > 0 weight penalty; `source` prefixes errors. An Error when sizes disagree, points are
/// not finite, the labels are all one class, no sample touches the grid or Newton's method does not
/// reach the gradient-norm tolerance.
template <int D>
OccupancyField<D> FitOccupancyField(const RbfGrid<D>& grid,
                                    const Eigen::Matrix<double, D, Eigen::Dynamic>& points,
                                    const std::vector<std::uint8_t>& occupied, double l2,
                                    const std::string& source);

/// Occupancy samples of an obstacle: the lattice lo + spacing * i over [lo, hi] (per axis, the
/// last point at most hi), occupied where signed_distance(s) <= 0. An Error for a non-finite or
/// empty box, a non-positive spacing or more than 10^7 samples.
template <int D>
void SampleObstacleOccupancy(const std::function<double(const Vec<D>&)>& signed_distance,
                             const Vec<D>& lo, const Vec<D>& hi, double spacing,
                             Eigen::Matrix<double, D, Eigen::Dynamic>* points,
                             std::vector<std::uint8_t>* occupied);

}  // namespace foresight::imitation
