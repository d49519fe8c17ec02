#pragma once
/// Trajectory-quality metrics of thesis ch 9 (sec. "Experimental Evaluation"), computed by this one
/// module for every method (GFCS, geometric fabrics, the OMPL planners): success, end-effector (EE)
/// path length, C-space path length, generation time, EE-LDJ and C-space LDJ, and their per-method
/// summary (summary.json).
///
/// Smoothness is the log dimensionless jerk with peak-speed normalisation (LDLJ-V of
/// Balasubramanian, Melendez-Calderon, Roby-Brami & Burdet 2015, "On the analysis of movement
/// smoothness", J. NeuroEng. Rehabil. 12:112, eq. for LDLJ with v_peak; Hogan & Sternad 2009 is the
/// amplitude form):
///
///   LDJ = -ln( (t2 - t1)^3 / v_peak^2 * integral_{t1}^{t2} |d^3 x / dt^3|^2 dt ),
///
/// |.| the Euclidean norm over the d dimensions of x (so |jerk|^2 sums over dimensions) and
/// v_peak = max_t |dx/dt| the peak speed. It is dimensionless, invariant to amplitude and duration
/// scaling, and larger (closer to zero for rest-to-rest movements) is smoother. Peak speed (not
/// amplitude A) normalises it because A is not defined for a multi-dimensional path that returns
/// near its start. A rest-to-rest minimum-jerk movement x(t) = A (10 s^3 - 15 s^4 + 6 s^5), s = t /
/// T, has LDJ = -ln(720 / 1.875^2) = -ln(204.8) ~ -5.322; n equal minimum-jerk sub-movements in
/// sequence have -ln(204.8 n^4).
///
/// Planner paths are geometric (waypoints, no time). They are timed by TimeParameterise: every
/// waypoint-to-waypoint segment is a rest-to-rest minimum-jerk (quintic) motion whose peak joint
/// speed meets the joint velocity limit. A planner path's LDJ therefore depends on this choice:
/// each waypoint is a stop, so a path of K waypoints is K - 1 sub-movements and scores roughly
/// -ln(204.8) - 4 ln(K - 1) for equal segments. Corners get finite jerk (no discontinuous
/// velocity), so the comparison with fabrics is not dominated by corner discontinuities, but fewer
/// waypoints (PlannerOptions::simplify) give a smoother score.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "inference/manipulation/joint_types.h"

namespace foresight::manipulation {

/// A trajectory sampled uniformly in time: sample i is at time i * dt.
struct TimedPath {
  Eigen::MatrixXd positions;  ///< [d x T] positions (rad for joints, m for the end effector)
  double dt = 0.01;           ///< sample spacing (s), > 0

  /// (T - 1) * dt (s); 0 for fewer than two samples.
  double duration() const;
};

/// Sum of the Euclidean distances between consecutive columns of `points` [d x T] (units of the
/// points: rad for a C-space path, m for an EE path). 0 for T < 2. Non-finite entries are an Error.
double PathLength(const Eigen::MatrixXd& points);

/// Why an LDJ is (not) defined.
enum class LdjStatus {
  kOk,
  kNotEvaluated,   ///< no path was given (a failed attempt, or no EE path)
  kTooFewSamples,  ///< fewer than kMinLdjSamples samples: no second-order jerk estimate
  kNoMotion,       ///< every sample equal (peak speed 0): the normalisation divides by zero
  kNonFinite,      ///< the jerk integral is 0 (e.g. constant velocity) or over/underflowed
};
const char* ToString(LdjStatus status);

/// Fewest samples for which LogDimensionlessJerk is defined (second-order one-sided stencils).
inline constexpr int kMinLdjSamples = 6;

/// The LDJ of a path, or why it is undefined. `value` is set iff status == kOk, so an undefined LDJ
/// cannot slip into a mean as NaN.
struct LdjResult {
  LdjStatus status = LdjStatus::kNotEvaluated;
  std::optional<double> value;
  bool ok() const { return status == LdjStatus::kOk; }
};

/// Log dimensionless jerk (peak-speed form, see the file comment) of `path` [d x T].
///
/// Derivatives are finite differences of the uniform samples, second-order accurate everywhere:
/// speed by central differences (x_{i+1} - x_{i-1}) / 2dt, one-sided (-3x_0 + 4x_1 - x_2) / 2dt at
/// the ends; jerk by the central five-point stencil (x_{i+2} - 2x_{i+1} + 2x_{i-1} - x_{i-2}) /
/// 2dt^3 for 2 <= i <= T-3 and the one-sided stencil (-5x_i + 18x_{i+1} - 24x_{i+2} + 14x_{i+3} -
/// 3x_{i+4}) / 2dt^3 for the first two samples, (5x_i - 18x_{i-1} + 24x_{i-2} - 14x_{i-3} +
/// 3x_{i-4}) / 2dt^3 for the last two. The integral of |jerk|^2 is the trapezoid rule over all T
/// samples; t2 - t1 = (T - 1) dt; v_peak is the largest sampled speed. On a minimum-jerk movement
/// the error is below 1e-3 with 100 samples per movement and falls as dt^2 (metrics_test).
/// Bad input (non-finite positions, dt not > 0 and finite) is an Error; degenerate input is a
/// status.
LdjResult LogDimensionlessJerk(const TimedPath& path);

/// Times a geometric (waypoint) path: each segment from waypoint k to k+1 is a rest-to-rest
/// minimum-jerk motion q(t) = q_k + (q_{k+1} - q_k)(10 s^3 - 15 s^4 + 6 s^5), s = t / T_k, whose
/// duration T_k brings the most constraining joint to its speed limit and keeps the others below
/// theirs (a min-jerk segment peaks at 1.875 * distance / duration): T_k = 1.875 max_j |dq_j| /
/// max_velocity_j,
/// rounded up to a whole number of steps dt so every waypoint is a sample (the limits then hold
/// with equality only up to that rounding). Segments of zero length are skipped. The samples lie on
/// the straight segments, so PathLength of the result equals PathLength(waypoints).
/// @param waypoints [kDof x K] joint angles (rad), K >= 1, finite.
/// @param max_velocity [kDof] joint speed limits (rad/s), > 0.
/// @param dt sample spacing of the result (s), > 0 (use the fabric integration step, 0.01 s).
/// @return [kDof x (1 + sum_k T_k / dt)] samples at spacing dt. Bad input is an Error.
TimedPath TimeParameterise(const Eigen::MatrixXd& waypoints, const JointVector& max_velocity,
                           double dt);

/// World position (m) of the end effector at joint angles q (forward kinematics lives elsewhere).
using EndEffectorFn = std::function<Eigen::Vector3d(const JointVector& q)>;

/// [3 x T] end-effector positions along `joints` [kDof x T] (same time samples).
Eigen::Matrix3Xd EndEffectorPath(const TimedPath& joints, const EndEffectorFn& ee_position);

/// The metrics of one attempt at one problem (thesis ch 9 table columns).
struct PathMetrics {
  bool success = false;  ///< the method reached the goal without collision (decided by the caller)
  double time_s = 0;     ///< time the method took to generate the trajectory (s), wall clock
  /// Set for a successful attempt whose trajectory was evaluated; empty otherwise.
  std::optional<double> cspace_length;  ///< rad (Euclidean in joint space)
  std::optional<double> ee_length;      ///< m; empty when no EE path was given
  std::optional<double> duration_s;     ///< trajectory duration (s), not generation time
  LdjResult cspace_ldj, ee_ldj;

  /// A failed attempt: only the time is known (metrics of failures are not aggregated).
  static PathMetrics Failure(double generation_time_s);
};

/// Metrics of a successful attempt from its joint trajectory alone; ee_length and ee_ldj are left
/// empty. @param joints [kDof x T] joint angles (rad), T >= 1. Bad input is an Error.
PathMetrics EvaluateJointPath(const TimedPath& joints, double generation_time_s);

/// Metrics of a successful attempt with its end-effector trajectory.
/// @param ee_positions [3 x T] EE positions (m) at the same time samples as `joints`.
PathMetrics EvaluatePath(const TimedPath& joints, const Eigen::Matrix3Xd& ee_positions,
                         double generation_time_s);
/// Same, with the EE positions from forward kinematics `ee_position` (a separate name: an Eigen
/// expression would otherwise convert to either argument type).
PathMetrics EvaluatePathWithKinematics(const TimedPath& joints, const EndEffectorFn& ee_position,
                                       double generation_time_s);

/// Mean and sample standard deviation of n values.
struct Stat {
  std::optional<double> mean;  ///< set iff n >= 1
  std::optional<double> std;   ///< sample std (divides by n - 1); set iff n >= 2
  int n = 0;
};
/// Stat of `values`; a non-finite value is an Error (never averaged silently).
Stat ComputeStat(const std::vector<double>& values);

/// One method's results over a problem set (summary.json). Every Stat is over the successful
/// problems only, and over those of them where the quantity is defined (an undefined LDJ or a
/// missing EE path lowers that Stat's n below `successes`).
struct MetricSummary {
  int problems = 0;
  int successes = 0;
  double success_rate = 0;  ///< successes / problems; 0 when problems == 0
  Stat ee_length, cspace_length, time_s, duration_s, ee_ldj, cspace_ldj;

  /// One line: "12/20 solved (60.0%), EE length 1.43 +- 0.50 m, ...".
  std::string BriefReport() const;
  /// One JSON object; an undefined mean or std is null.
  std::string ToJson() const;
};

MetricSummary Summarise(const std::vector<PathMetrics>& attempts);

}  // namespace foresight::manipulation
