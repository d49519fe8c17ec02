#pragma once
/// ORCA: optimal reciprocal collision avoidance (van den Berg, Guy, Lin, Manocha, "Reciprocal
/// n-body collision avoidance", ISRR 2011), the baseline crowd-navigation papers report against.
/// Written here from the paper (RVO2 is not packaged).
///
/// For agent A and neighbour B (relative position p = p_B - p_A, relative velocity
/// v = v_A - v_B, combined radius r) the velocity obstacle VO^tau is the truncated cone of relative
/// velocities that collide within the time horizon tau: the cone from the origin tangent to the
/// disc D(p, r) cut off by the disc D(p / tau, r / tau). u is the smallest change of v onto the
/// boundary of VO^tau and n the boundary's outward normal there; A takes the share `responsibility`
/// of the change (0.5: B also runs ORCA; 1.0: B does not react):
///   ORCA_A|B = { v' : (v' - (v_A + responsibility u)) . n >= 0 }            (paper, eq. 5)
/// When A and B already overlap, the cut-off uses the time step dt instead of tau (the pair
/// separates within one step). The new velocity is the one closest to the preferred velocity inside
/// every half-plane and the max-speed disc: a 2-D incremental program (each violated constraint
/// moves the optimum onto its line, a 1-D problem). When the half-planes leave nothing inside the
/// disc, a 3-D program minimises the largest violation (signed distance into a half-plane) over
/// the disc, solved the same way with the violation as the third variable (paper, sec. 5.3).

#include <Eigen/Core>
#include <vector>

#include "inference/navigation/controller.h"
#include "inference/navigation/goal_distance.h"
#include "inference/navigation/static_clearance.h"

namespace foresight::nav {

/// One neighbour as A sees it.
struct OrcaNeighbour {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  ///< m, world
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  ///< m/s, world
  double radius = 0.4;                                 ///< m
  /// Share of the avoidance A takes for this neighbour: 0.5 when it also avoids, 1.0 when not.
  double responsibility = 0.5;
};

struct OrcaOptions {
  double time_horizon = 2.0;  ///< tau (s): collisions later than this are ignored
  double max_speed = 1.0;     ///< m/s, radius of the speed disc
  double dt = 0.1;            ///< s, time step used when the agents already overlap
};

/// Allowed half-plane { x : (x - point) . normal >= 0 }; `normal` is a unit vector.
struct OrcaHalfPlane {
  Eigen::Vector2d point = Eigen::Vector2d::Zero(), normal = Eigen::Vector2d::UnitX();
  /// Signed distance of x into the allowed side (negative: violated by that much, m/s).
  double Margin(const Eigen::Vector2d& x) const { return (x - point).dot(normal); }
};

/// Reused buffers of OrcaVelocity (no allocation once they have grown to the neighbour count).
struct OrcaWorkspace {
  std::vector<OrcaHalfPlane> planes;  ///< the ORCA half-planes of the last call, one per neighbour
  std::vector<OrcaHalfPlane> projected;  ///< the 3-D fallback's projected constraints
};

/// The ORCA half-plane of A induced by one neighbour (paper, eq. 5; overlap: cut-off at dt).
OrcaHalfPlane OrcaConstraint(const Eigen::Vector2d& position, const Eigen::Vector2d& velocity,
                             double radius, const OrcaNeighbour& neighbour,
                             const OrcaOptions& options);

struct OrcaResult {
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  ///< m/s, |velocity| <= max_speed
  bool feasible = true;      ///< false: the 3-D fallback (least largest violation) chose `velocity`
  double max_violation = 0;  ///< largest violation of a half-plane at `velocity` (0 when feasible)
};

/// ORCA for one holonomic agent: the velocity closest to `preferred` inside every neighbour's
/// half-plane and the disc |v| <= max_speed, else the one with the least largest violation.
/// Pure; never throws for finite input. `workspace` (optional) keeps the buffers and, after the
/// call, the half-planes.
/// @param position [2] m; @param velocity [2] current velocity (m/s); @param radius m
/// @param preferred [2] preferred velocity (m/s), clipped to the disc when nothing constrains it
OrcaResult OrcaVelocity(const Eigen::Vector2d& position, const Eigen::Vector2d& velocity,
                        double radius, const Eigen::Vector2d& preferred,
                        const std::vector<OrcaNeighbour>& neighbours, const OrcaOptions& options,
                        OrcaWorkspace* workspace = nullptr);

/// The 2-D program alone: the point of { |x| <= max_speed } and every half-plane closest to
/// `preferred`. @return false (and `*x` untouched beyond the last feasible optimum) when empty.
bool OrcaClosestFeasible(const std::vector<OrcaHalfPlane>& planes, double max_speed,
                         const Eigen::Vector2d& preferred, Eigen::Vector2d* x);

/// Options of OrcaController (config block `orca:`).
struct OrcaControllerOptions {
  double time_horizon = 2.0;       ///< tau (s)
  double responsibility = 1.0;     ///< share the robot takes per pedestrian (0.5: reciprocal)
  double heading_gain = 2.0;       ///< omega = heading_gain * heading error (1/s), then clamped
  double safety_margin = 0.1;      ///< m added to each pedestrian's radius
  double dt = 0.1;                 ///< control period (s)
  double robot_radius = 0.4;       ///< m
  double pedestrian_radius = 0.4;  ///< m
  double epsilon = 0.25;           ///< swept-occupancy threshold of a static collision (as SPAN's)
  ControlLimits limits;
  /// Describe problems (names the offending field) or return an empty string.
  std::string Problems() const;
};

/// ORCA as a navigation controller for the unicycle robot. Each cycle:
/// - pedestrian velocities: the difference of the last two observed points / observation_step
///   (zero with a single point);
/// - preferred velocity: v_max (less within 1 s of the goal) along the steepest descent of the
///   geodesic goal distance (GoalDistanceField, as the reactive baseline), straight to the goal
///   without a static map;
/// - ORCA (OrcaVelocity) over the observed pedestrians, each with `responsibility`; the robot's own
///   velocity is the previous command along its heading;
/// - unicycle control: heading error e to the ORCA velocity, omega = heading_gain e clamped,
///   v = |v_orca| cos e clamped to [0, v_max]; it reverses (v < 0, turning toward the opposite
///   direction) only when the ORCA velocity points backwards and standing still would violate a
///   half-plane;
/// - static obstacles (ORCA itself sees only pedestrians): a command whose Euler step enters the
///   swept static field (value > epsilon, or larger than the current value when already inside)
///   has its v halved up to four times, then set to 0 (turning in place never moves the disc).
class OrcaController final : public NavigationController {
 public:
  /// @param field swept static map (null or empty: none); must outlive the controller.
  OrcaController(const StaticCollisionField* field, OrcaControllerOptions options);
  std::string name() const override { return "orca"; }
  void Prepare(const Eigen::Vector2d& goal) override;
  ControlOutcome Compute(const NavigationInput& input) override;

  /// The preferred velocity at `x` toward `goal` (m/s).
  Eigen::Vector2d PreferredVelocity(const Eigen::Vector2d& x, const Eigen::Vector2d& goal) const;
  /// The unicycle command following `velocity` from `robot` (no static check).
  Control Follow(const UnicycleState& robot, const Eigen::Vector2d& velocity) const;
  /// The ORCA result of the last cycle.
  const OrcaResult& last() const { return last_; }
  const OrcaWorkspace& workspace() const { return ws_; }

 private:
  const StaticCollisionField* field_;
  OrcaControllerOptions options_;
  GoalDistanceField goal_field_;
  mutable occupancy::MapWorkspace map_ws_;
  Eigen::MatrixXd clean_rows_;
  Eigen::Matrix2Xd current_;
  std::vector<OrcaNeighbour> neighbours_;
  OrcaWorkspace ws_;
  OrcaResult last_;
  Control previous_;
};

}  // namespace foresight::nav
