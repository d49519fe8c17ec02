#pragma once
/// The imitation transform psi_i of diffeomorphic templates (thesis ch 8, "Learning Infinitesimal
/// Generators from Demonstrations"): the time-T flow of the RBF vector field
///   V(s) = W' phi(s)      (phi: rbf_grid.h, W [m x D])
/// by K explicit Euler steps of h = T / K:
///   s_0 = x,  s_{k+1} = s_k + h V_{g(k)}(s_k),  psi(x) = s_K,
/// with its Jacobian propagated exactly through the same steps (the discrete variational equation):
///   J_0 = I,  J_{k+1} = (I + h DV_{g(k)}(s_k)) J_k,  DV(s) = sum_t W_t (d phi_t/ds)'  [D x D].
/// Segments: with S >= 1 segments the field is piecewise constant in time, one weight matrix W_g
/// per segment, step k using segment g(k) = floor(k S / K) (so 1 <= S <= K). S = 1 is the thesis's
/// stationary generator; S > 1 composes S flows of RBF fields (each a diffeomorphism, so psi is
/// one too) and deforms further at the same step cost. The weights are stacked [S m x D], segment g
/// in rows g m .. (g + 1) m - 1.
/// Inverse: the exact inverse of the Euler map, step by step from s_K back to s_0, each step
/// solving s_k = s_{k+1} - h V(s_k) by fixed-point iteration started at the thesis's backward step
/// s_{k+1} - h V(s_{k+1}) (gamma(-t, .)). The Euler map is invertible where h Lip(V) < 1; the
/// iteration then contracts. A step that does not converge, or det(I + h DV) <= 0, means the
/// settings make the flow non-invertible: Inverse returns false and CheckInvertible reports it.
/// The cut-off makes V jump by up to discontinuity() = 2 truncation max_t ||W_t|| (rbf_grid.h):
/// near a cut-off sphere the Euler map then has no exact inverse, and the iteration settles into an
/// oscillation of about h discontinuity(), which it accepts (the inverse is exact to that level;
/// elsewhere to `tolerance`).
///
/// The natural-gradient imitation system (thesis eq. naturalDesc with the errata's form, solve with
/// J, never form G^-1 = (J'J)^-1):
///   f_i(x) = -speed * J(x)^-1 grad Phi(psi(x)),  Phi(z) = ||z - z_e||,  z_e = psi(x_goal),
/// so grad Phi = (z - z_e) / ||z - z_e|| (0 at z = z_e). speed > 0 is a constant time scale
/// (learned with W); it does not change the integral curves or stability.

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "inference/imitation/rbf_grid.h"

namespace foresight::imitation {

template <int D>
struct FlowSettings {
  double time = 1.0;  ///< T > 0
  int steps = 10;     ///< K >= 1 Euler steps
  int segments = 1;   ///< S, 1 <= S <= K: time segments with their own weights (file comment)
};

/// The segment g(k) = floor(k S / K) of Euler step k (file comment).
template <int D>
int SegmentOfStep(const FlowSettings<D>& s, int step) {
  return static_cast<int>(static_cast<long long>(step) * s.segments / s.steps);
}

/// Per-caller scratch, made by RbfFlow::MakeWorkspace. Empty since the field is summed row by row
/// on the stack (RbfGrid::ForEachRow); kept so that callers and the interface stay as they are.
template <int D>
struct FlowWorkspace {};

template <int D>
class RbfFlow {
 public:
  RbfFlow() = default;
  /// @param weights [S m x D], m = grid.size(), S = settings.segments; all finite (an Error naming
  /// `source` otherwise).
  RbfFlow(RbfGrid<D> grid, Eigen::MatrixXd weights, FlowSettings<D> settings,
          const std::string& source = "rbf flow");

  const RbfGrid<D>& grid() const { return grid_; }
  const Eigen::MatrixXd& weights() const { return weights_; }
  const FlowSettings<D>& settings() const { return settings_; }
  FlowWorkspace<D> MakeWorkspace() const;
  /// Bound on the jump of V across cut-off spheres: 2 truncation max_t ||W_t|| (see above).
  double discontinuity() const { return discontinuity_; }
  /// The round-trip error psi^-1(psi(x)) - x the truncation allows: h discontinuity per step over
  /// K steps, with a safety factor of 10 (10 T discontinuity). Export and load both grant it.
  double TruncationAllowance() const { return 10 * settings_.time * discontinuity_; }

  /// V_g(s) of segment g and optionally DV_g(s) (nullptr: skipped). No allocation.
  Vec<D> Field(const Vec<D>& s, FlowWorkspace<D>* ws, Mat<D>* jacobian = nullptr,
               int segment = 0) const;
  /// psi(x) and optionally its Jacobian J = d psi / dx. No allocation.
  Vec<D> Forward(const Vec<D>& x, FlowWorkspace<D>* ws, Mat<D>* jacobian = nullptr) const;
  /// psi^-1(z) into *x; false when a step's fixed point does not converge to `tolerance` (relative:
  /// corrections <= tolerance (1 + ||s||)) within `max_iterations`, nor stagnates at the truncation
  /// level h discontinuity() (non-invertible settings). No allocation.
  bool Inverse(const Vec<D>& z, FlowWorkspace<D>* ws, Vec<D>* x, double tolerance = 1e-12,
               int max_iterations = 100) const;

 private:
  RbfGrid<D> grid_;
  Eigen::MatrixXd weights_;                        // [S m x D]
  Eigen::Matrix<double, D, Eigen::Dynamic> rows_;  // W' [D x S m]: W_t contiguous per state
  FlowSettings<D> settings_;
  double discontinuity_ = 0;
};

/// Result of CheckInvertible over a set of points.
struct InvertibilityReport {
  bool ok = true;
  int points = 0;                   ///< points checked
  double max_roundtrip_error = 0;   ///< max ||psi^-1(psi(x)) - x||
  double min_step_determinant = 1;  ///< min over points and steps of det(I + h DV(s_k))
  int failed_points = 0;            ///< points whose inverse did not converge
  std::string Describe() const;     ///< one line for logs and errors
};
/// Checks psi^-1(psi(x)) = x to `tolerance` and det(I + h DV) > 0 at every Euler step of every
/// point [D x n] (e.g. a grid over the workspace and the demonstrations).
template <int D>
InvertibilityReport CheckInvertible(const RbfFlow<D>& flow,
                                    const Eigen::Matrix<double, D, -1>& points, double tolerance);

namespace detail {
/// Inverts the K-step Euler map s_{k+1} = s_k + h V_k(s_k) of any field `field(s, k)` -> V_k(s)
/// (k: the forward step being inverted): step by
/// step from s_K = z, each by the fixed point s_k = s_{k+1} - h V(s_k) started at the backward step
/// s_{k+1} - h V(s_{k+1}). Converged when a correction is at most tolerance (1 + ||s||), or when
/// the iteration has stopped contracting (a correction >= 0.99 times the previous one) at a level
/// of at most `slack` (h times the field's jump at cut-offs: the oscillation across a cut-off
/// sphere). False when a step does not converge or becomes non-finite.
template <int D, typename Field>
bool InvertEulerMap(const Vec<D>& z, int steps, double h, const Field& field, double tolerance,
                    double slack, int max_iterations, Vec<D>* x) {
  Vec<D> next = z;
  for (int k = steps - 1; k >= 0; --k) {
    Vec<D> s = next - h * field(next, k);
    bool converged = false;
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0; it < max_iterations; ++it) {
      const Vec<D> update = next - h * field(s, k);
      const double change = (update - s).norm();
      s = update;
      if (!std::isfinite(change)) return false;
      if (change <= tolerance * (1 + s.norm()) || (change <= slack && change >= 0.99 * previous)) {
        converged = true;
        break;
      }
      previous = change;
    }
    if (!converged) return false;
    next = s;
  }
  *x = next;
  return true;
}
}  // namespace detail

/// The stable imitation system f_i (see the file comment).
template <int D>
class ImitationSystem {
 public:
  ImitationSystem() = default;
  ImitationSystem(RbfFlow<D> flow, Vec<D> goal, double speed);
  const RbfFlow<D>& flow() const { return flow_; }
  const Vec<D>& goal() const { return goal_; }
  const Vec<D>& goal_image() const { return goal_image_; }  ///< z_e = psi(goal)
  double speed() const { return speed_; }
  /// f_i(x); optionally also z = psi(x). No allocation.
  Vec<D> Velocity(const Vec<D>& x, FlowWorkspace<D>* ws, Vec<D>* z = nullptr) const;

 private:
  RbfFlow<D> flow_;
  Vec<D> goal_ = Vec<D>::Zero(), goal_image_ = Vec<D>::Zero();
  double speed_ = 1;
};

}  // namespace foresight::imitation
