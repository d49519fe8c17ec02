#pragma once
/// Collision avoidance for the whole arm in C-space (thesis ch 8, "Building Infinitesimal
/// Generators for Collision Avoidance in C-space"), on a 6-DoF SerialChain with body points x_j(q).
///
/// - The C-space occupancy field (thesis: V^o_q(q) = grad_q sum_j f_map(x_j(q))) and its Jacobian,
///   from p, grad p = g_j and Hess p = H_j of an occupancy field at the body points:
///     V_q(q) = sum_j J_j' g_j,   dV_q/dq = sum_j [J_j' H_j J_j + sum_k (dJ_j/dq_k)' g_j e_k']
///   (the second term in closed form: serial_chain.h, AddPointPotential). dV_q/dq is the Hessian
///   of sum_j p(x_j(q)), hence symmetric. The body points enter by their centres; to keep the
///   balls out, fit the occupancy of the obstacle inflated by the ball radius.
/// - CSpaceObstacleTransform psi_o^q: the time-T flow of V_q by K explicit Euler steps of h = T/K,
///     q_0 = p,  q_{k+1} = q_k + h V_q(q_k),  psi_o^q(p) = q_K,
///   with the exact Jacobian of the Euler map J_0 = I, J_{k+1} = (I + h dV_q(q_k)) J_k (as
///   ObstacleTransform, transforms.h; Forward stops once V_q and dV_q are exactly zero, e.g. no
///   body point within the map's support: the remaining steps would change nothing). Inverse: the
///   exact inverse of the Euler map, each step q_k = q_{k+1} - h V_q(q_k) by fixed-point iteration
///   from q_{k+1} - h V_q(q_{k+1}); false when a step does not converge (h Lip(V_q) >= 1 there: the
///   settings are not invertible). The outer configurations p = psi_o^-1(q) are the inner ones
///   flowed down the occupancy of the body points, so the outer system keeps the arm away from the
///   obstacle. Goal gate (optional, length l > 0): V_q is multiplied by w(q) = 1 - exp(-r^2 / (2
///   l^2)), r = ||x_ee(q) - x_goal||, so the field vanishes on every configuration whose end
///   effector is at the goal; dV = w dV_q + V_q grad w',  grad w = exp(-r^2 / (2 l^2)) J_ee' (x_ee
///   - x_goal) / l^2. Without it a map that is not negligible at the goal moves the composed
///   system's equilibrium: psi_o fixes those configurations only where V_q = 0, and the outer arm
///   then stops short of the goal. With it psi_o fixes the goal set pointwise, so x_ee(psi_o(p)) is
///   the goal exactly when x_ee(p) is (an addition to the thesis's V^o_q, which assumes p(o) = 0
///   there).
/// - CSpaceSystem: thesis eq. CspaceNG with the errata's pull-back (never form G^-1):
///     q = psi_o^q(p),  q_dot = J_ee(q)^+ f_world(x_ee(q)),  p_dot = J_o(p)^-1 q_dot,
///   J^+ = J' (J J' + lambda^2 I)^-1 (damped least squares; lambda = 0 is the thesis's
///   Moore-Penrose pseudo-inverse J'(J J')^-1, which blows up at singular configurations). Without
///   an obstacle transform p = q. f_world is the end-effector imitation system f_i (an
///   ImitationSystem<3> learned in normalised coordinates s = (x - offset) scale):
///     f_world(x) = f_i((x - offset) scale) / scale.
///   p are the executed joint angles: the rollout returns them and the end-effector path x_ee(p).

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

#include "inference/imitation/occupancy_field.h"
#include "inference/imitation/rbf_flow.h"
#include "inference/imitation/serial_chain.h"
#include "inference/imitation/transforms.h"

namespace foresight::imitation {

/// The C-space field of any smooth point potential: Kinematics at q, then for every body point
/// `field(x_j, with_hessian, &value)` (value: OccupancyValue<3>, p, gradient and, when asked, the
/// Hessian at x_j); V = sum_j J_j' g_j and, when dV is not null, dV = the Jacobian of V. Returns
/// sum_j p(x_j). No allocation (given a `field` that allocates nothing).
template <typename PointField>
double CSpacePotentialField(const SerialChain& chain, const ArmVector& q, const PointField& field,
                            ChainData* data, ArmVector* V, ArmMatrix* dV) {
  Kinematics(chain, q, data);
  V->setZero();
  if (dV != nullptr) dV->setZero();
  double total = 0;
  OccupancyValue<3> value;
  for (int j = 0; j < chain.num_points(); ++j) {
    field(Vec<3>(data->p.col(j)), dV != nullptr, &value);
    total += value.p;
    AddPointPotential(*data, j, value.gradient, value.hessian, V, dV);
  }
  return total;
}

/// Scratch of one CSpaceObstacleTransform caller.
struct CSpaceTransformWorkspace {
  ChainData chain;
  std::unique_ptr<RbfFeatures<3>> features;
};

/// The goal gate of CSpaceObstacleTransform (file comment): the end-effector goal in the world
/// and l (m); length 0 = no gate.
using GoalGate = ObstacleGate<3>;

/// psi_o^q (see the file comment).
class CSpaceObstacleTransform {
 public:
  CSpaceObstacleTransform() = default;
  /// `settings`: time T > 0 and steps K >= 1 (an Error naming the value otherwise); `chain` with
  /// at least one body point; `gate`: finite goal, length >= 0.
  CSpaceObstacleTransform(SerialChain chain, OccupancyField<3> field,
                          FlowSettings<kArmDof> settings, GoalGate gate = {});

  const SerialChain& chain() const { return chain_; }
  const OccupancyField<3>& field() const { return field_; }
  const FlowSettings<kArmDof>& settings() const { return settings_; }
  const GoalGate& gate() const { return gate_; }
  CSpaceTransformWorkspace MakeWorkspace() const;

  /// V_q(q) (gated when a gate is set) and optionally its Jacobian dV_q/dq [6 x 6] and
  /// sum_j p(x_j(q)) (never gated). No allocation.
  /// @param q [6] joint angles (rad)
  ArmVector Field(const ArmVector& q, CSpaceTransformWorkspace* ws, ArmMatrix* jacobian = nullptr,
                  double* occupancy = nullptr) const;
  /// q = psi_o^q(p) and optionally J_o = d psi_o^q / dp. No allocation.
  ArmVector Forward(const ArmVector& p, CSpaceTransformWorkspace* ws,
                    ArmMatrix* jacobian = nullptr) const;
  /// p = (psi_o^q)^-1(q) (exact inverse of the Euler map); false when a step's fixed point does
  /// not converge to `tolerance` (max-norm, rad) within `max_iterations`. No allocation.
  bool Inverse(const ArmVector& q, CSpaceTransformWorkspace* ws, ArmVector* p,
               double tolerance = 1e-12, int max_iterations = 100) const;

 private:
  SerialChain chain_;
  OccupancyField<3> field_;
  FlowSettings<kArmDof> settings_;
  GoalGate gate_;
};

/// World <-> normalised coordinates of the imitation model: s = (x - offset) scale.
struct TaskNormalisation {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< world point mapped to s = 0 (m)
  double scale = 1;                                  ///< model units per metre, > 0
  Vec<3> ToModel(const Eigen::Vector3d& x) const { return (x - offset) * scale; }
  Eigen::Vector3d ToWorld(const Vec<3>& s) const { return s / scale + offset; }
};

/// Scratch of one CSpaceSystem caller.
struct CSpaceSystemWorkspace {
  ChainData chain;                    ///< kinematics at the inner configuration q
  FlowWorkspace<3> imitation;         ///< f_i
  CSpaceTransformWorkspace obstacle;  ///< psi_o^q (empty without one)
};

/// The C-space system (see the file comment).
class CSpaceSystem {
 public:
  static constexpr double kDefaultDamping = 1e-3;  ///< lambda (m)

  /// `obstacle` (optional) must be built on an arm with the same joints as `chain`;
  /// normalisation.scale > 0 and offset finite; damping >= 0 finite. Errors name the value.
  CSpaceSystem(SerialChain chain, ImitationSystem<3> imitation, TaskNormalisation normalisation,
               std::optional<CSpaceObstacleTransform> obstacle = std::nullopt,
               double damping = kDefaultDamping);

  const SerialChain& chain() const { return chain_; }
  const ImitationSystem<3>& imitation() const { return imitation_; }
  const TaskNormalisation& normalisation() const { return normalisation_; }
  const std::optional<CSpaceObstacleTransform>& obstacle() const { return obstacle_; }
  double damping() const { return damping_; }
  /// The imitation goal in the world (m).
  Eigen::Vector3d goal() const { return normalisation_.ToWorld(imitation_.goal()); }

  CSpaceSystemWorkspace MakeWorkspace() const;
  /// f_world(x): the end-effector velocity the imitation system asks for at x (m/s). No allocation.
  Eigen::Vector3d TaskVelocity(const Eigen::Vector3d& x, CSpaceSystemWorkspace* ws) const;
  /// J_ee(q)^+ f_world(x_ee(q)) (rad/s): the inner system on Q. No allocation.
  ArmVector InnerVelocity(const ArmVector& q, CSpaceSystemWorkspace* ws) const;
  /// p_dot (rad/s) at the outer configuration p. No allocation.
  ArmVector Velocity(const ArmVector& p, CSpaceSystemWorkspace* ws) const;
  /// The inner configuration q = psi_o^q(p) (p without an obstacle transform).
  ArmVector Inner(const ArmVector& p, CSpaceSystemWorkspace* ws) const;

 private:
  SerialChain chain_;
  ImitationSystem<3> imitation_;
  TaskNormalisation normalisation_;
  std::optional<CSpaceObstacleTransform> obstacle_;
  double damping_ = kDefaultDamping;
};

/// Why a C-space rollout stopped.
enum class CSpaceStop {
  kReached,    ///< ||x_ee(p) - goal|| <= goal_tolerance
  kMaxSteps,   ///< max_steps Euler steps without reaching the goal
  kNonFinite,  ///< a velocity was not finite (path ends before it)
};
const char* CSpaceStopName(CSpaceStop stop);

struct CSpaceRollout {
  Eigen::Matrix<double, kArmDof, Eigen::Dynamic> joints;  ///< [6 x n] configurations p (rad)
  Eigen::Matrix3Xd end_effector;                          ///< [3 x n] x_ee(p) (m)
  CSpaceStop stop = CSpaceStop::kMaxSteps;
  bool reached() const { return stop == CSpaceStop::kReached; }
};

/// Rolls out p_dot = system.Velocity(p) from the arm configuration `start` by explicit Euler
/// steps of settings.dt (each joint step at most settings.max_step_length rad when that is > 0)
/// until the end effector is within settings.goal_tolerance (m) of
/// system.goal(), a velocity is not finite, or settings.max_steps. The path includes the start.
CSpaceRollout RollOutCSpace(const CSpaceSystem& system, const ArmVector& start,
                            const RolloutSettings& settings);

}  // namespace foresight::imitation
