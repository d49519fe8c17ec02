#pragma once
/// The CL-RRT* baseline of thesis ch 5 ("Experimental Evaluation"; Kuwata et al. 2008 with an
/// asymptotically optimal planner): every cycle, OMPL's RRT* plans a path in the plane from the
/// robot to the goal with the pedestrians as disc obstacles at their current positions and the
/// swept static map, within a planning budget (0.1 s, and an iteration cap so runs are comparable
/// across machines); a pure-pursuit tracker turns the path into (v, omega). When no path is found
/// the robot stays put (thesis: "the robot will remain at its current pose"). As in CL-RRT, the
/// best partial path towards the goal counts as found when it makes progress (min_progress).

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "inference/navigation/controller.h"
#include "inference/navigation/static_clearance.h"

namespace foresight::nav {

struct ClRrtStarOptions {
  double budget_s = 0.1;        ///< planning time budget per cycle (wall clock)
  int max_iterations = 1500;    ///< RRT* iteration cap per cycle
  double range = 1.0;           ///< RRT* extension step (m)
  double goal_tolerance = 0.3;  ///< goal region radius of the planner (m)
  double lookahead = 0.8;       ///< pure-pursuit look-ahead distance (m)
  /// A partial plan (no path reaches the goal region) is followed when its end is at least this
  /// much closer to the goal than the robot (m); otherwise the robot stays put.
  double min_progress = 0.3;
  /// Radius around the robot where the static map is not checked (m): the tracker may graze the
  /// epsilon band at corners; pedestrians are always checked.
  double start_exemption = 0.15;
  double robot_radius = 0.4, pedestrian_radius = 0.4, epsilon = 0.25;
  double check_resolution = 0.05;  ///< motion validity checking step (m)
  ControlLimits limits;
  std::string Problems() const;
};

/// Pure pursuit (Amidi 1991) on a polyline path [2 x n] from the robot: steer towards the point
/// `lookahead` ahead of the path point closest to the robot. Turns in place when that point lies
/// behind; slows down on the final `lookahead` metres.
Control PurePursuit(const UnicycleState& robot, const Eigen::Matrix2Xd& path, double lookahead,
                    const ControlLimits& limits);

class ClRrtStarController final : public NavigationController {
 public:
  /// @param extent [x_min, x_max, y_min, y_max] of the planning space (m).
  ClRrtStarController(const StaticCollisionField* field, const Eigen::Vector4d& extent,
                      ClRrtStarOptions options, std::uint64_t seed);
  ~ClRrtStarController() override;
  std::string name() const override { return "cl_rrt_star"; }
  ControlOutcome Compute(const NavigationInput& input) override;
  /// The path of the last successful plan [2 x n] (empty when the last plan failed).
  const Eigen::Matrix2Xd& path() const { return path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Eigen::Matrix2Xd path_;
};

}  // namespace foresight::nav
