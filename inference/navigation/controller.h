#pragma once
/// What every navigation controller sees each cycle and what it answers. Controllers are stateful
/// (warm starts, tracked paths): make one per episode. Compute() never throws for finite input;
/// a failed solve returns a stop command with a status other than kSolved and a message saying why.

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "inference/navigation/unicycle.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::nav {

struct NavigationInput {
  UnicycleState robot;
  Eigen::Vector2d goal = Eigen::Vector2d::Zero();
  /// Observed pedestrians, one row each: x_1, y_1, ..., x_p, y_p (oldest first, one point every
  /// `observation_step` s, the last at the current time); [N x 2p]. N may be 0.
  const Eigen::MatrixXd* past_rows = nullptr;  ///< null: no pedestrians
  double observation_step = 0.1;
};

/// How a control cycle ended (expected outcomes are values, not exceptions).
enum class ControlStatus {
  kSolved,        ///< a control was found
  kNoFinitePlan,  ///< every candidate was infeasible or non-finite: stop
  kNoPath,        ///< the planner found no path that makes progress: stay put
  kError,         ///< the cycle failed (e.g. malformed observations): stop; see `message`
};
const char* ToString(ControlStatus status);

struct ControlOutcome {
  Control command;
  ControlStatus status = ControlStatus::kSolved;  ///< not kSolved: the command stops the robot
  std::string message;  ///< why a cycle was not solved (empty when solved)
  int evaluations = 0;  ///< objective evaluations (SPAN, reactive) or planner iterations (CL-RRT*)
  /// Time-to-collision of the chosen control (inf: none within the horizon; NaN: the controller
  /// does not report one).
  double tau = std::numeric_limits<double>::quiet_NaN();
  double cost = 0;        ///< objective value of the chosen control
  bool fallback = false;  ///< the command came from a fallback (SPAN's escape), not the objective
  bool solved() const { return status == ControlStatus::kSolved; }
  /// A stop command with `status` and `message`.
  static ControlOutcome Stop(ControlStatus status, std::string message);
};

class NavigationController {
 public:
  virtual ~NavigationController() = default;
  virtual std::string name() const = 0;
  /// Per-goal set-up outside the timed control loop (e.g. the goal-distance field). Optional.
  virtual void Prepare(const Eigen::Vector2d& goal) {}
  virtual ControlOutcome Compute(const NavigationInput& input) = 0;
  /// The pedestrians' predicted futures of the last cycle, for rendering: the first
  /// `PredictedPedestrians()` entries are valid. Controllers that do not predict return null.
  virtual const std::vector<TrajectoryDistribution>* Predictions() const { return nullptr; }
  virtual int PredictedPedestrians() const { return 0; }
};

}  // namespace foresight::nav
