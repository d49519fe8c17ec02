#pragma once
/// A geometric fabric for the Panda (thesis ch 9, "Preliminaries: Geometric Fabrics"; Ratliff,
/// Van Wyk et al., "Geometric Fabrics: Generalizing Classical Mechanics to Capture the Physics of
/// Behavior", RA-L 2022). Terms, each a task map phi_i(q) with Jacobian J_i, curvature J_i' q_d,
/// a priority metric M_i and a geometry x_dd_i = h_i(x, x_d):
///
///   base        x = q                       M = base_inertia I,            h = 0
///   limits      x = q_j - lower_j, upper_j - q_j (14 scalars)
///   obstacles   x = d_W(p_s(q)) - r_s       one per body sphere s (closest obstacle)
///   self        x = |p_a - p_b| - r_a - r_b one per checked sphere pair
///
/// The three barrier families share one scalar form (homogeneous of degree 2 in x_d, repulsive
/// only while approaching):
///   h(x, x_d) = k x_d^2 / x,  M(x, x_d) = lambda max(0, 1/x - 1/range) [x_d < 0]
/// (the metric falls to zero at `range`, so terms switch on continuously).
///
/// Fusion (thesis eq. in "Fusion"): q_dd_g = (sum J'MJ)^-1 sum J'M(h - J' q_d).
/// Energisation with the Euclidean kinetic energy L_e = |q_d|^2 / 2 keeps the speed the geometry
/// would change: q_dd_e = q_dd_g - q_d (q_d . q_dd_g) / |q_d|^2 (Ratliff et al.'s Energize with
/// M_e = I; the geometry only bends paths).
/// Forcing by a C-space attractor to the command c, potential psi(x) = k (|x| + log(1 + exp(-2 a
/// |x|)) / a), x = q - c, so grad psi = k tanh(a |x|) x / |x| (smooth at the goal), with metric
/// M_psi = (m_far + (m_near - m_far) exp(-(|x| / w)^2)) I, and damping beta(|x|):
///   q_dd = q_dd_e - M^-1 grad psi - beta q_d,  M = base + sum J'MJ + M_psi.
/// Near obstacles the barrier metrics dominate M, so the forcing towards them is suppressed and
/// the motion slows down (the thesis's reason why GFCOP solutions keep clear of obstacles).
///
/// Integration (thesis eq. "integrate"): semi-implicit Euler at `dt`; rollout_t is the first time
/// |q_t - c|_2 < goal_tolerance (via_tolerance towards an intermediate command), capped at t_max.
/// A rollout also stops when a sphere penetrates an
/// obstacle or another sphere, a joint leaves its limits, or the state becomes non-finite: these
/// are statuses, never exceptions, and NaN never propagates.
///
/// Model/workspace contract: a Fabric holds references to the robot and world (both must outlive
/// it) and is immutable; each thread uses its own FabricWorkspace. Acceleration() and Rollout()
/// do not allocate.

#include <Eigen/Core>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "core/config.h"
#include "inference/manipulation/joint_types.h"
#include "inference/manipulation/robot_model.h"
#include "inference/manipulation/world.h"

namespace foresight::manipulation {

/// A repulsive barrier family: h = gain x_d^2 / x, M = metric max(0, 1/x - 1/range) [x_d < 0].
struct BarrierParams {
  double gain = 1.0;    ///< k of the geometry (1)
  double metric = 1.0;  ///< lambda of the metric (m or rad)
  double range = 0.2;   ///< distance beyond which the term is off (m or rad)

  template <class A>
  void Serialize(A* a) {
    a->Visit("gain", &gain, config::Range::NonNegative(), "geometry gain k in h = k xd^2 / x");
    a->Visit("metric", &metric, config::Range::NonNegative(),
             "metric scale lambda in M = lambda (1/x - 1/range) while approaching");
    a->Visit("range", &range, config::Range::Positive(), "activation distance");
  }
};

struct FabricParams {
  double base_inertia = 0.2;                ///< metric of the C-space base term
  BarrierParams limits{1.0, 0.5, 0.1};      ///< joint-limit repulsion (rad)
  BarrierParams obstacles{5.0, 2.0, 0.05};  ///< body sphere vs world (m)
  /// sphere pairs (m); chosen on problems 1-50 by experiments/fabric_select.sh (results/
  /// fabric_select.md: with {1, 0.5, 0.03} most collisions were self-collisions)
  BarrierParams self{10.0, 5.0, 0.05};
  double attractor_gain = 10.0;                ///< k of psi (rad/s^2)
  double attractor_sharpness = 10.0;           ///< a of psi (1/rad)
  double attractor_metric_far = 0.3;           ///< m_far
  double attractor_metric_near = 2.0;          ///< m_near
  double attractor_metric_width = 1.0 / 0.75;  ///< w (rad)
  double damping = 3.0;                        ///< beta far from the command (1/s)
  double damping_near = 6.0;                   ///< extra beta close to the command (1/s)
  double damping_near_radius = 0.1;            ///< |x| where the extra damping is half on (rad)
  double dt = 0.01;                            ///< integration step (s), thesis 0.01
  double t_max = 7.0;                          ///< time budget per command (s), thesis 7
  double goal_tolerance = 0.05;                ///< epsilon of rollout_t (rad, 2-norm)
  /// epsilon of rollout_t towards an intermediate command (Rollout(..., kVia)). The thesis has one
  /// epsilon for every command, so the default equals goal_tolerance; a larger one hands over to
  /// the next command while still moving (a departure, chosen on validation when changed).
  double via_tolerance = 0.05;
  /// Stall test (0 = off, the thesis): a rollout towards the goal (CommandRole::kGoal; an
  /// intermediate rollout's end state starts the next one, so those always run on) whose distance
  /// d to its command has not made progress within the last `stall_window` seconds ends as a
  /// timeout at once, charged t_max as if it had run on (Rollout's `stalled`). Progress from the
  /// last anchor distance d_a means d < d_a - min(stall_progress, stall_fraction (d_a -
  /// tolerance)): a fixed step far from the command, a share of what is left near it (a slow final
  /// approach still progresses). Not in the thesis: it only saves the steps of rollouts held in a
  /// local minimum, and is adopted only where validation shows the same outcomes (docs/gfcs.md).
  double stall_window = 0.0;
  double stall_progress = 0.01;  ///< rad (2-norm of q - command)
  double stall_fraction = 0.2;   ///< of the distance left beyond the tolerance
  /// Skip the spheres and pairs of bodies whose bounding spheres are out of range (FabricProbe).
  /// The same rollouts either way (tested bit for bit); false is the reference the benchmark
  /// compares against.
  bool broad_phase = true;

  template <class A>
  void Serialize(A* a) {
    a->Visit("base_inertia", &base_inertia, config::Range::Positive(), "metric of the base term");
    a->Visit("limits", &limits, config::Range::Any(), "joint-limit repulsion (rad)");
    a->Visit("obstacles", &obstacles, config::Range::Any(), "body-sphere obstacle repulsion (m)");
    a->Visit("self", &self, config::Range::Any(), "self-collision repulsion (m)");
    a->Visit("attractor_gain", &attractor_gain, config::Range::Positive(),
             "attractor potential gain k (rad/s^2)");
    a->Visit("attractor_sharpness", &attractor_sharpness, config::Range::Positive(),
             "attractor smoothing a (1/rad)");
    a->Visit("attractor_metric_far", &attractor_metric_far, config::Range::Positive(),
             "attractor metric far from the command");
    a->Visit("attractor_metric_near", &attractor_metric_near, config::Range::Positive(),
             "attractor metric at the command");
    a->Visit("attractor_metric_width", &attractor_metric_width, config::Range::Positive(),
             "width of the attractor metric's transition (rad)");
    a->Visit("damping", &damping, config::Range::NonNegative(),
             "damping far from the command (1/s)");
    a->Visit("damping_near", &damping_near, config::Range::NonNegative(),
             "extra damping close to the command (1/s)");
    a->Visit("damping_near_radius", &damping_near_radius, config::Range::Positive(),
             "distance where the extra damping is half on (rad)");
    a->Visit("dt", &dt, config::Range::OpenClosed(0.0, 0.1), "integration step (s)");
    a->Visit("t_max", &t_max, config::Range::OpenClosed(0.0, 600.0), "time budget per command (s)");
    a->Visit("goal_tolerance", &goal_tolerance, config::Range::Positive(),
             "rollout_t tolerance on |q - command| (rad)");
    a->Visit(
        "via_tolerance", &via_tolerance, config::Range::Positive(),
        "rollout_t tolerance towards an intermediate command (rad; the thesis: goal_tolerance)");
    a->Visit("stall_window", &stall_window, config::Range::Closed(0.0, 600.0),
             "end a rollout towards the goal as a timeout (charged t_max) when it has made no "
             "progress (stall_progress, stall_fraction) for this long (s); 0 = off (the thesis)");
    a->Visit("stall_progress", &stall_progress, config::Range::Positive(),
             "progress towards the command that resets the stall window, far from it (rad)");
    a->Visit("stall_fraction", &stall_fraction, config::Range::OpenClosed(0.0, 1.0),
             "progress that resets the stall window near the command: this share of the "
             "distance left beyond the tolerance");
    a->Visit("broad_phase", &broad_phase, config::Range::Any(),
             "skip the spheres and pairs of bodies whose bounding spheres are out of range (the "
             "same rollouts; false: every distance, the benchmark's reference)");
  }
};

/// A scalar task variable of a barrier term and its pull-back: x, x_d = J q_d, J, and J' q_d
/// (the curvature, so that x_dd = J q_dd + J' q_d).
struct ScalarTask {
  double x = 0, xd = 0;
  Eigen::Matrix<double, 1, kDof> J = Eigen::Matrix<double, 1, kDof>::Zero();
  double jdq = 0;
};

/// Clearance of a body sphere: x = d_W(p) - radius, J = n' J_p,
/// J' q_d = n' (J_p' q_d) + p_d' H_d p_d (H_d, the distance Hessian, by a central difference of
/// the exact gradient along p_d). @param p_W [3] centre (m), @param J_p [3x7] its Jacobian,
/// @param jdq_p [3] its J' q_d, @param qd [7] joint velocities.
ScalarTask SphereObstacleTask(const World& world, const Eigen::Vector3d& p_W, double radius,
                              const PointJacobian& J_p, const Eigen::Vector3d& jdq_p,
                              const JointVector& qd);

/// The same for a sphere whose centre's world distance `signed_distance` and closest obstacle
/// `closest` (World::SignedDistance's) are known: the normal and the curvature come from that
/// obstacle alone (three single-primitive queries instead of three over the world). The result
/// equals the overload above wherever the closest obstacle is the same within kCurvatureStep
/// (1e-5 m) of p_W along its velocity; across such a switch the world's minimum has a kink and
/// this one keeps the one-sided (smooth) curvature.
ScalarTask SphereObstacleTask(const World& world, double signed_distance, int closest,
                              const Eigen::Vector3d& p_W, double radius, const PointJacobian& J_p,
                              const Eigen::Vector3d& jdq_p, const JointVector& qd);

/// Distance between two spheres' surfaces: x = |p_a - p_b| - r_a - r_b, n = (p_a - p_b)/|.|,
/// J = n'(J_a - J_b), J' q_d = n'(jdq_a - jdq_b) + (|v|^2 - (n'v)^2) / |p_a - p_b|, v = (J_a -
/// J_b) q_d.
ScalarTask SpherePairTask(const Eigen::Vector3d& p_a, double r_a, const PointJacobian& J_a,
                          const Eigen::Vector3d& jdq_a, const Eigen::Vector3d& p_b, double r_b,
                          const PointJacobian& J_b, const Eigen::Vector3d& jdq_b,
                          const JointVector& qd);

/// Metric of a barrier term at (x, x_d): lambda max(0, 1/x - 1/range) while approaching, else 0.
double BarrierMetric(const BarrierParams& p, double x, double xd);

/// How a rollout towards one command ended.
enum class RolloutStatus {
  kReached,     ///< |q - command| < the tolerance (goal_ or via_tolerance) before t_max
  kTimeout,     ///< t_max elapsed; the state at t_max is returned
  kCollision,   ///< a sphere penetrated an obstacle or another sphere
  kJointLimit,  ///< a joint left its limits
  kNonFinite,   ///< the acceleration became non-finite (the last finite state is returned)
  kStopped,     ///< the caller's time limit (below t_max) passed first: the outcome is unknown
};
inline constexpr int kRolloutStatusCount = static_cast<int>(RolloutStatus::kStopped) + 1;
const char* ToString(RolloutStatus status);

/// What a rollout's command is: the goal (goal_tolerance) or an intermediate one (via_tolerance).
enum class CommandRole { kGoal, kVia };

struct RolloutResult {
  RolloutStatus status = RolloutStatus::kTimeout;
  double t = 0;                          ///< integration time used (s); t_max on timeout
  JointVector q = JointVector::Zero();   ///< terminal configuration
  JointVector qd = JointVector::Zero();  ///< terminal velocity
  int steps = 0;         ///< integration steps taken (fewer than t / dt when stalled)
  bool stalled = false;  ///< a timeout declared by the stall test (t is t_max)
  bool ok() const { return status == RolloutStatus::kReached || status == RolloutStatus::kTimeout; }
};

/// What the last Acceleration() saw: clearances for the rollout's collision checks, and the fused
/// metric and energised geometry for tests.
///
/// Broad phase: the spheres of one body (those moved by the same arm joints) lie in a bounding
/// sphere fixed to the body. Since a signed distance is 1-Lipschitz, an obstacle farther than
/// obstacles.range from a body's bounding sphere is farther than that from each of its spheres:
/// a body's spheres are measured against the obstacles within its reach only (none: skipped;
/// World::SignedDistanceAmong, the same numbers as the world's minimum), and a sphere farther than
/// self.range from another body's bounding sphere has no pair within range with that body's
/// spheres: their distances are not computed.
/// Skipped spheres and pairs could not add a term or collide, so M and the forces are those of the
/// full sums.
struct FabricProbe {
  Eigen::Matrix<double, kDof, kDof> metric = Eigen::Matrix<double, kDof, kDof>::Zero();  ///< M
  JointVector energized = JointVector::Zero();  ///< q_dd_e (before forcing and damping)
  /// min over the spheres the broad phase kept of d_W(p_s) - r_s (m): exact whenever the true
  /// minimum is below obstacles.range; otherwise at least that (+inf when no sphere was kept)
  double min_obstacle_clearance = 0;
  /// min over the pairs the broad phase kept (m): exact whenever the true minimum over checked
  /// pairs is below self.range; otherwise at least that
  double min_self_clearance = 0;
  int obstacle_distances = 0;  ///< world distance queries made (bodies and spheres)
  int pair_distances = 0;      ///< sphere-pair distances computed
  int active_obstacle_terms = 0;
  int active_self_terms = 0;
};

/// Work buffers of one caller (one per thread).
struct FabricWorkspace {
  KinematicsData kinematics;
  FabricProbe probe;
  /// The broad phase's buffers (sized by Fabric::MakeWorkspace for its world): the distance from
  /// a body's bounding sphere to each obstacle, and per body the obstacles within its reach.
  std::vector<double> bound_distances;  ///< [num_obstacles]
  std::vector<int> candidates;          ///< [(kDof + 1) x num_obstacles]
};

class Fabric {
 public:
  /// `robot` and `world` must outlive the fabric. Throws Error for invalid params.
  Fabric(const RobotModel& robot, const World& world, const FabricParams& params);

  const FabricParams& params() const { return params_; }
  const RobotModel& robot() const { return robot_; }
  const World& world() const { return world_; }
  FabricWorkspace MakeWorkspace() const;

  /// q_dd of the forced, energised, damped fabric at (q, q_d) towards `command`.
  /// @param q [7] joint angles (rad), @param qd [7] joint velocities (rad/s),
  /// @param command [7] attractor configuration (rad). Returns false (qdd untouched) when the
  /// result is non-finite or the metric is not positive definite.
  bool Acceleration(const JointVector& q, const JointVector& qd, const JointVector& command,
                    FabricWorkspace* ws, JointVector* qdd) const;

  /// Integrates from (q0, qd0) towards `command` until rollout_t (thesis), a collision, a limit
  /// violation or a non-finite state. When `path` is given, every state's q is appended to it
  /// (this allocates; leave it null in optimisation loops). A caller that only needs to know
  /// whether the rollout lasts longer than `stop_beyond_s` gets kStopped at the first step whose
  /// time exceeds it (the rollout is identical up to there). `role` picks rollout_t's tolerance.
  /// With params().stall_window > 0 a goal rollout that stops approaching the goal ends early as
  /// a timeout (see FabricParams::stall_window).
  RolloutResult Rollout(const JointVector& q0, const JointVector& qd0, const JointVector& command,
                        FabricWorkspace* ws, std::vector<JointVector>* path = nullptr,
                        double stop_beyond_s = std::numeric_limits<double>::infinity(),
                        CommandRole role = CommandRole::kGoal) const;

 private:
  /// The spheres of one body and a sphere around them, fixed to the body (centre p_BC in the body
  /// frame; every sphere s of the body has |p_s - c| + r_s <= radius).
  struct BodyBound {
    int body = 0;
    Eigen::Vector3d p_BC = Eigen::Vector3d::Zero();
    double radius = 0;
  };
  /// Fills body_bounds_, sphere_bound_ and pair_runs_ from the robot's spheres (FK at q = 0).
  void BuildBroadPhase();
  /// The broad phase's obstacle side: per bound k, the obstacles within its reach (ascending) in
  /// ws->candidates[k * num_obstacles ..], their number in (*count)[k]; every obstacle without
  /// the broad phase (then the list is not written: a sphere's query is the world's minimum).
  /// @param c_W [bounds] bounding-sphere centres in W.
  void SelectObstacles(const std::array<Eigen::Vector3d, kDof + 1>& c_W, FabricWorkspace* ws,
                       std::array<int, kDof + 1>* count) const;

  const RobotModel& robot_;
  const World& world_;
  FabricParams params_;
  std::vector<BodyBound> body_bounds_;  ///< bodies that carry spheres
  std::vector<int> sphere_bound_;       ///< [num_spheres] index into body_bounds_
  /// Maximal runs of consecutive self-collision pairs (in the robot's order) of one sphere with
  /// the spheres of one other body: [begin, end), the sphere and the other body's bound. The broad
  /// phase skips a whole run when the sphere is out of range of that bound.
  struct PairRun {
    int begin = 0, end = 0, sphere = 0, other_bound = 0;
  };
  std::vector<PairRun> pair_runs_;
};

}  // namespace foresight::manipulation
