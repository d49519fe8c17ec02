#pragma once
/// The RBF flow's training objective (models/imitation/flow_net.h) and its exact gradient by a
/// hand-written reverse pass, LibTorch-free: the same function as RbfFlowNet's Velocity +
/// VelocityLoss + InvertibilityPenalty under autograd, computed sparsely (a sample touches only
/// the inducing states within the kernel's cut-off, RbfGrid::Evaluate) and without a graph.
///
/// Loss of a batch (x_i, v_i), i < B, with penalty points y_r, r < R:
///   L = (1/B) sum_i ||f(x_i) - v_i||^2 + w_P P,
///   f(x) = -speed J^-1 g,  g = u / sqrt(||u||^2 + eps^2),  u = psi(x) - psi(x_goal),
///   P = (1/K) sum_k (1/N) sum_{p in [x; y]} max(0, h ||DV_{g(k)}(s_k(p))||_F - kappa)^2,
/// with psi, J, DV, the segments g(k) and h = T/K as flow_net.h. Reverse pass per sample, Euler
/// step k from K-1 down to 0, with A_k = DV(s_k), the adjoints G_s = dL/ds_{k+1}, G_J = dL/dJ_{k+1}
/// and G_A = dL/dA_k (from J_{k+1} = (I + h A_k) J_k and from the penalty at s_k):
///   G_A = h G_J J_k' + (penalty) 2 w_P/(K N) max(0, e) h A_k / ||A_k||_F,  e = h ||A_k||_F - kappa
///   dL/dW_t += h phi_t G_s + G_A dphi_t          (t within the cut-off of s_k)
///   dL/ds_k  = G_s + h A_k' G_s + sum_t H_t (G_A' W_t),
///   dL/dJ_k  = (I + h A_k)' G_J,
/// H_t = phi_t (4 gamma^2 r_t r_t' - 2 gamma I) the Hessian of phi_t,
/// r_t = s_k - c_t, dphi_t = -2 gamma phi_t r_t, W_t the t-th row of the step's segment weights.
/// Samples are processed in fixed chunks whose gradients are summed in chunk order, so the result
/// does not depend on the number of threads.

#include <Eigen/Core>
#include <memory>
#include <string>

#include "inference/imitation/rbf_grid.h"

namespace foresight::imitation {

/// Row-major [n, d] matrices (the layout of a contiguous [n, d] tensor).
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// One evaluation's data (row-major views; the dimension is the objective's).
struct FlowObjectiveBatch {
  const double* x = nullptr;        ///< [B, d] positions
  const double* v = nullptr;        ///< [B, d] demonstrated velocities
  int batch = 0;                    ///< B >= 1
  const double* goal = nullptr;     ///< [d]
  const double* penalty = nullptr;  ///< [R, d] extra penalty points (may be null when R = 0)
  int penalty_count = 0;            ///< R >= 0
  double penalty_weight =
      0;  ///< w_P >= 0 (0: no penalty, as ImitationTask's, training/diffeo/imitation_task.h)
};

/// The objective of one flow (grid, time, steps, segments); thread-safe (const).
class FlowObjective {
 public:
  virtual ~FlowObjective() = default;
  virtual int dimension() const = 0;
  /// Inducing states m (the weights have S m rows).
  virtual int num_centres() const = 0;
  virtual int segments() const = 0;
  virtual int steps() const = 0;
  virtual double time() const = 0;
  virtual double gamma() const = 0;
  virtual double cutoff_radius() const = 0;
  /// Inducing state t in [0, m) (RbfGrid order), `dimension()` coordinates into `out`.
  virtual void Centre(int t, double* out) const = 0;
  /// L (file comment) at weights W [S m, d] row-major and log_speed. When grad_weights is not null
  /// it receives dL/dW (row-major [S m, d], overwritten) and *grad_log_speed dL/dlog_speed.
  /// `threads` >= 1 share the samples. Bad shapes or counts are an Error.
  virtual double Evaluate(const double* weights, double log_speed, const FlowObjectiveBatch& batch,
                          int threads, double* grad_weights, double* grad_log_speed) const = 0;
};

/// The objective on `grid` (the centres RbfFlowNet holds, in RbfGrid order) for time T > 0,
/// K >= 1 Euler steps and S in [1, K] segments; kappa = the per-step Lipschitz bound of the
/// invertibility penalty, eps = the goal regulariser (flow_net.h's kStepLipschitz, kGoalEpsilon).
/// Errors name the bad value.
template <int D>
std::shared_ptr<const FlowObjective> MakeFlowObjective(const RbfGridSpec<D>& grid, double time,
                                                       int steps, int segments, double kappa,
                                                       double goal_epsilon);

}  // namespace foresight::imitation
