#pragma once
/// The obstacle cost operator of structurally constrained prediction (thesis ch 7, eqs. Costeqn,
/// costEqnTime): the time-averaged probability of collision of a predicted trajectory distribution,
///   C_r = 1/K sum_k  int N(x; mu_r(t_k), Sigma_r(t_k)) p(m = 1 | x) dx        (rectangle rule in
///   t)
///       ~ 1/K sum_k  sum_q beta_q p(m = 1 | mu_r(t_k) + s_r(t_k) L_V z_q)       (2-D
///       Gauss-Hermite)
/// with mu_r(t) = M_r' phi(t), Sigma_r(t) = s_r(t)^2 V_r = (s_r(t) L_V)(s_r(t) L_V)' (the change of
/// variables through the Cholesky factor), and the mixture's C = sum_r alpha_r C_r. The occupancy
/// p(m = 1 | x) and its gradient come from any occupancy-map engine (inference/mapping).
/// Analytic gradients (tested against finite differences), with x_q = mu + s L_V z_q and
/// g_q = grad p(x_q):
///   dC/dM = 1/K sum_k sum_q beta_q phi(t_k) g_q',   dC/dL_V = 1/K sum_k sum_q beta_q s g_q z_q',
///   dC/dlog_u_j = 1/K sum_k sum_q beta_q (g_q' L_V z_q) u_j phi_j(t_k)^2 / (2 s).

#include <Eigen/Core>
#include <vector>

#include "core/rbf.h"
#include "inference/constrained/component.h"
#include "inference/constrained/gauss_hermite.h"
#include "inference/mapping/occupancy_map.h"

namespace foresight::constrained {

/// Where the rectangle rule of C = 1/T int_0^T (...) dt puts its K points on (0, T]:
/// kRight at t_k = k T / K (the predicted steps when K = f: first order, error O(1/K));
/// kMidpoint at t_k = (k - 1/2) T / K (second order, O(1/K^2), for the same K evaluations).
enum class TimeRule { kRight, kMidpoint };

/// The K time points of `rule` on (0, horizon]. Error unless K >= 1 and horizon > 0 (finite).
Eigen::VectorXd RuleTimes(TimeRule rule, double horizon, int k);

class CollisionCost {
 public:
  struct Workspace {
    occupancy::MapWorkspace map;
    occupancy::MapQueryBatch batch;
    Eigen::Matrix2Xd points;  ///< abscissae of one time step [2 x q]
    /// [2 x K] added to the mean at each time (e.g. origin + v t_k); empty = zero. A predicted
    /// distribution's position mean is origin + v t + M' phi(t): the offset is constant in the
    /// parameters, so the gradients do not change.
    Eigen::Matrix2Xd offset;
  };

  /// @param map occupancy map (kept by pointer; must outlive this). @param basis the trajectory
  /// basis phi(t). @param times the K time points of the rectangle rule (>= 1, finite).
  /// @param order Gauss-Hermite points per axis (>= 1). Error naming the bad argument.
  CollisionCost(const occupancy::Map* map, const TimeBasis& basis, Eigen::VectorXd times,
                int order);

  int order() const { return order_; }
  int basis() const { return basis_.size(); }
  const Eigen::VectorXd& times() const { return times_; }
  Workspace MakeWorkspace() const;

  /// C_r of one component (mean M' phi(t_k) + ws->offset.col(k)); with `gradient` not null also its
  /// derivatives (resized). No allocation once the workspace and the gradient are sized. Error when
  /// the component's basis differs or ws->offset is neither empty nor [2 x K].
  double Component(const ComponentParams& c, Workspace* ws, ComponentGradient* gradient) const;
  /// sum_r alpha_r C_r (every component with the workspace's offset).
  double Mixture(const std::vector<double>& alpha, const std::vector<ComponentParams>& components,
                 Workspace* ws) const;
  /// The abscissae x_q at every time of component c, [2 x K q] (for pictures); `offset` as
  /// Workspace::offset ([2 x K] or empty = zero).
  Eigen::Matrix2Xd Abscissae(const ComponentParams& c,
                             const Eigen::Matrix2Xd& offset = Eigen::Matrix2Xd()) const;

 private:
  const occupancy::Map* map_ = nullptr;
  TimeBasis basis_;
  Eigen::VectorXd times_;
  Eigen::MatrixXd phi_;  ///< [K x m], phi(t_k)'
  int order_ = 0;
  StandardNormalRule2 rule_;
};

}  // namespace foresight::constrained
