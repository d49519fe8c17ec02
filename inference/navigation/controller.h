#pragma once
/// What every navigation controller sees each cycle and what it answers. Controllers are stateful
/// (warm starts, tracked paths): make one per episode. Compute() never throws for finite input;
/// a failed solve returns a stop command with `solved = false`.

#include <Eigen/Core>
#include <string>

#include "inference/navigation/unicycle.h"

namespace foresight::nav {

struct NavigationInput {
  UnicycleState robot;
  Eigen::Vector2d goal = Eigen::Vector2d::Zero();
  /// Observed pedestrians, one row each: x_1, y_1, ..., x_p, y_p (oldest first, one point every
  /// `observation_step` s, the last at the current time); [N x 2p]. N may be 0.
  const Eigen::MatrixXd* past_rows = nullptr;  ///< null: no pedestrians
  double observation_step = 0.1;
};

struct ControlOutcome {
  Control command;
  bool solved = true;     ///< false: no acceptable control was found (the command stops the robot)
  int evaluations = 0;    ///< objective evaluations (SPAN, reactive) or planner iterations (CL-RRT*)
  double tau = 0;         ///< time-to-collision of the chosen control (inf: none within the horizon)
  double cost = 0;        ///< objective value of the chosen control
};

class NavigationController {
 public:
  virtual ~NavigationController() = default;
  virtual std::string name() const = 0;
  /// Per-goal set-up outside the timed control loop (e.g. the goal-distance field). Optional.
  virtual void Prepare(const Eigen::Vector2d& goal) {}
  virtual ControlOutcome Compute(const NavigationInput& input) = 0;
};

}  // namespace foresight::nav
