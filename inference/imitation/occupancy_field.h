#pragma once
/// A continuous occupancy map p(o = 1 | s) = sigmoid(w' phi(s) + b) on Gaussian RBF features
/// (rbf_grid.h) in D = 2 or 3 dimensions: the Hilbert map (Ramos & Ott 2015) the obstacle
/// transforms of thesis ch 8 differentiate. Gives p, grad p and the Hessian of p exactly:
///   f = w' phi + b,  grad f = sum_t w_t (-2 g phi_t r_t),
///   Hess f = sum_t w_t phi_t (4 g^2 r_t r_t' - 2 g I),
///   grad p = p (1 - p) grad f,  Hess p = p (1 - p) [(1 - 2 p) grad f grad f' + Hess f].
/// In 2-D it reads the mapping engine's Hilbert-map artifacts (FromHingeMap: the same features,
/// tested against HingeMap::Query), so a map trained by `foresight train configs/occupancy/...`
/// serves as the obstacle map; the imitation pipeline trains its own with FitOccupancyField
/// (models/imitation/occupancy_fit.h) from occupancy samples of the new obstacle.
///
/// Tabulate (2-D): the feature sums are replaced by a bicubic Hermite table of the logit f, built
/// once from the exact f, f_x, f_y and f_xy at nodes `spacing` apart over the features' support.
/// Between the nodes f is the C1 interpolant, so p and grad p stay continuous and the Hessian is
/// that of the interpolant; the error falls as spacing^4 (f), ^3 (grad f) and ^2 (Hess f) against
/// the kernel width 1 / sqrt(2 gamma), and a query costs a few dozen flops and one exponential
/// instead of four exponentials and a sum over the cut-off window.

#include <Eigen/Core>
#include <memory>
#include <string>

#include "inference/imitation/rbf_grid.h"

namespace foresight::occupancy {
class HingeMap;
}

namespace foresight::imitation {

struct LogitTable;  // occupancy_field.cc

template <int D>
struct OccupancyValue {
  double p = 0;                      ///< p(o = 1 | s)
  Vec<D> gradient = Vec<D>::Zero();  ///< d p / d s
  Mat<D> hessian = Mat<D>::Zero();   ///< d^2 p / d s^2 (only when asked)
};

template <int D>
class OccupancyField {
 public:
  OccupancyField() = default;
  /// @param weights [m] (m = grid.size()), bias: finite (an Error naming `source` otherwise).
  OccupancyField(RbfGrid<D> grid, Eigen::VectorXd weights, double bias,
                 const std::string& source = "occupancy field");
  /// The field of a 2-D Hilbert map of the mapping engine (kind occupancy.hilbert; the Bayesian
  /// kinds by their mean weights). D = 2 only.
  static OccupancyField FromHingeMap(const occupancy::HingeMap& map);

  const RbfGrid<D>& grid() const { return grid_; }
  const Eigen::VectorXd& weights() const { return weights_; }
  double bias() const { return bias_; }
  /// Scratch per caller. Evaluate and Probability no longer use it (they sum the features row by
  /// row, RbfGrid::ForEachRow); kept for the interface and for callers listing features.
  std::unique_ptr<RbfFeatures<D>> MakeWorkspace() const;

  /// p, grad p and (with_hessian) Hess p at s (from the table where there is one). No allocation.
  void Evaluate(const Vec<D>& s, RbfFeatures<D>* ws, bool with_hessian,
                OccupancyValue<D>* out) const;
  double Probability(const Vec<D>& s, RbfFeatures<D>* ws) const;

  /// From now on evaluates through a bicubic Hermite table with nodes `spacing` apart (2-D only;
  /// 0 removes the table). Error naming `source` for a 3-D field, a spacing that is negative or
  /// not finite, or a table of more than 2^22 nodes. Copies share the (immutable) table.
  void Tabulate(double spacing, const std::string& source = "occupancy field");
  double table_spacing() const;  ///< 0: exact feature sums

 private:
  RbfGrid<D> grid_;
  Eigen::VectorXd weights_;
  double bias_ = 0;
  std::shared_ptr<const LogitTable> table_;
};

}  // namespace foresight::imitation
