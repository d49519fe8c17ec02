#pragma once
/// Diffeomorphic transforms that generalise an imitation system (thesis ch 8), and their
/// composition by the pull-back of the errata: for x = psi(y) and a system x_dot = f(x) on the
/// inner manifold, the system on the outer one is
///   y_dot = J_psi(y)^-1 f(psi(y)),
/// which keeps the stability of f (its trajectories are the images of f's under psi^-1).
///
/// - ObstacleTransform<D> psi_o: the time-T flow of V_o(s) = grad p(o = 1 | s) of an occupancy
///   field (eq. map), K Euler steps with the exact Jacobian J_{k+1} = (I + h Hess p(s_k)) J_k.
///   Flowing -V_o (psi_o^-1) lowers occupancy, so the outer trajectories bend around the obstacle.
///   Outside the map's support (no feature within the cut-off) V_o and its Jacobian are exactly
///   zero and stay so (the field is autonomous): Forward stops there, with the same values. An
///   optional goal gate (ObstacleGate) makes psi_o fix the goal.
/// - BiasTransform<D> psi_b: the flow of an RBF field V_b = W' phi fitted by ridge regression to
///   unit vectors pointing away from a user point s_tar on samples of a region (thesis
///   "Infinitesimal Generators for User-Specified Bias"): the outer system is pulled toward s_tar.
/// - ComposedSystem<D>: y_dot = J_o(y)^-1 f_inner(psi_o(y)), where f_inner is an ImitationSystem
///   or another ComposedSystem (any type with Velocity(x, ws)). Transforms apply in the order
///   given.
///
/// Rollout: explicit Euler with step dt (length capped by max_step_length) from y_0 until
/// ||y - goal|| <= goal_tolerance or max_steps;
/// non-finite velocities stop the rollout (reported, never returned as a path).

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "inference/imitation/occupancy_field.h"
#include "inference/imitation/rbf_flow.h"

namespace foresight::imitation {

/// Optional goal gate of ObstacleTransform: the field is multiplied by
/// w(s) = 1 - exp(-||s - goal||^2 / (2 length^2)), so psi_o fixes the goal exactly and the composed
/// system keeps the imitation system's equilibrium. Without it a map whose gradient is not exactly
/// zero at the goal (a soft map reaches across the whole region) moves the equilibrium to
/// psi_o^-1(goal): rollouts then settle a little off the goal (as the C-space gate, cspace.h).
/// length 0: no gate.
template <int D>
struct ObstacleGate {
  Vec<D> goal = Vec<D>::Zero();  ///< the point the gate closes at
  double length = 0;             ///< l, >= 0
  /// w(x) = 1 - e with e = exp(-||x - goal||^2 / (2 l^2)), and dw/dx = e (x - goal) / l^2 into
  /// `gradient` (not null). Only for length > 0.
  double Weight(const Vec<D>& x, Vec<D>* gradient) const {
    const Vec<D> d = x - goal;
    const double l2 = length * length;
    const double e = std::exp(-d.squaredNorm() / (2 * l2));
    *gradient = (e / l2) * d;
    return 1 - e;
  }
};

template <int D>
class ObstacleTransform {
 public:
  ObstacleTransform() = default;
  /// `gate`: finite goal, length >= 0 (an Error naming the value otherwise).
  ObstacleTransform(OccupancyField<D> field, FlowSettings<D> settings, ObstacleGate<D> gate = {});
  const OccupancyField<D>& field() const { return field_; }
  const FlowSettings<D>& settings() const { return settings_; }
  const ObstacleGate<D>& gate() const { return gate_; }
  /// The (gated) field V_o(s) = w(s) grad p(s) and, when `jacobian` is not null, its Jacobian
  /// w Hess p + grad p grad w'. No allocation.
  Vec<D> Field(const Vec<D>& s, RbfFeatures<D>* ws, Mat<D>* jacobian = nullptr) const;
  std::unique_ptr<RbfFeatures<D>> MakeWorkspace() const { return field_.MakeWorkspace(); }
  /// psi_o(y) and optionally J = d psi_o / dy. No allocation.
  Vec<D> Forward(const Vec<D>& y, RbfFeatures<D>* ws, Mat<D>* jacobian = nullptr) const;
  /// Exact inverse of the Euler map (as RbfFlow::Inverse); false when not invertible.
  bool Inverse(const Vec<D>& x, RbfFeatures<D>* ws, Vec<D>* y, double tolerance = 1e-12,
               int max_iterations = 100) const;
  /// Approximate bound on the jump of grad p across cut-off spheres (the inverse is exact to about
  /// h times this; see rbf_flow.h): 2 truncation max_t |w_t| (gamma cutoff_radius + 1).
  double discontinuity() const { return discontinuity_; }

 private:
  OccupancyField<D> field_;
  FlowSettings<D> settings_;
  ObstacleGate<D> gate_;
  double discontinuity_ = 0;
};

/// Fits the bias field: samples [D x n] of the region, target s_tar; ridge weight `lambda`.
template <int D>
RbfFlow<D> FitBiasTransform(const RbfGrid<D>& grid, const Eigen::Matrix<double, D, -1>& samples,
                            const Vec<D>& target, double lambda, FlowSettings<D> settings);

/// Workspace of one composed evaluation (allocated once by the caller).
template <int D>
struct ComposedWorkspace {
  FlowWorkspace<D> imitation;
  std::vector<std::unique_ptr<RbfFeatures<D>>> obstacle;  // one per obstacle transform
  std::vector<FlowWorkspace<D>> bias;                     // one per bias transform
};

/// One outer transform in a chain: either an obstacle or a bias transform.
template <int D>
struct OuterTransform {
  enum class Type { kObstacle, kBias } type = Type::kObstacle;
  ObstacleTransform<D> obstacle;
  RbfFlow<D> bias;
};

/// f_i composed with outer transforms psi_1 (innermost) ... psi_n (outermost):
///   y_n_dot = J_n^-1 J_{n-1}^-1 ... J_1^-1 f_i(x), evaluated from the outside in.
template <int D>
class ComposedSystem {
 public:
  ComposedSystem(ImitationSystem<D> imitation, std::vector<OuterTransform<D>> outer);
  ComposedWorkspace<D> MakeWorkspace() const;
  const ImitationSystem<D>& imitation() const { return imitation_; }
  /// Velocity of the outermost system at y. No allocation.
  Vec<D> Velocity(const Vec<D>& y, ComposedWorkspace<D>* ws) const;
  /// The point on the imitation manifold that y maps to (psi_1 o ... o psi_n)(y).
  Vec<D> Inner(const Vec<D>& y, ComposedWorkspace<D>* ws) const;

 private:
  ImitationSystem<D> imitation_;
  std::vector<OuterTransform<D>> outer_;
};

struct RolloutSettings {
  double dt = 0.01;              ///< Euler step (time units of the system)
  int max_steps = 5000;          ///< hard stop
  double goal_tolerance = 0.01;  ///< reached when ||y - goal|| <= this
  /// Largest step length ||dt v|| (0: no limit): a longer step is shortened along v, so the path
  /// follows the integral curve where the velocity is large (steep transforms) without
  /// overshooting; only the time parametrisation changes.
  double max_step_length = 0;
};

template <int D>
struct Rollout {
  Eigen::Matrix<double, D, -1> path;  ///< [D x (steps + 1)] including the start
  bool reached = false;
  bool finite = true;  ///< false: a velocity was not finite; path ends before it
};

/// Rolls out y_dot = velocity(y) from `start` (explicit Euler).
template <int D>
Rollout<D> RollOut(const std::function<Vec<D>(const Vec<D>&)>& velocity, const Vec<D>& start,
                   const Vec<D>& goal, const RolloutSettings& settings);

}  // namespace foresight::imitation
