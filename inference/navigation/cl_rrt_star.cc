#include "inference/navigation/cl_rrt_star.h"

#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <sstream>

#include "core/error.h"
#include "inference/navigation/span_controller.h"

namespace foresight::nav {

namespace ob = ompl::base;
namespace og = ompl::geometric;

std::string ClRrtStarOptions::Problems() const {
  std::ostringstream e;
  if (!(budget_s > 0) || !std::isfinite(budget_s))
    e << "budget_s = " << budget_s << " must be > 0; ";
  if (max_iterations < 1) e << "max_iterations = " << max_iterations << " must be >= 1; ";
  if (!(range > 0)) e << "range = " << range << " must be > 0; ";
  if (!(goal_tolerance > 0)) e << "goal_tolerance must be > 0; ";
  if (!(lookahead > 0)) e << "lookahead must be > 0; ";
  if (!(check_resolution > 0)) e << "check_resolution must be > 0; ";
  if (!(epsilon > 0 && epsilon < 1)) e << "epsilon = " << epsilon << " must be in (0, 1); ";
  return e.str();
}

Control PurePursuit(const UnicycleState& robot, const Eigen::Matrix2Xd& path, double lookahead,
                    const ControlLimits& limits) {
  if (path.cols() == 0) return {0, 0};
  const Eigen::Vector2d p = robot.position();
  // Closest vertex, then walk `lookahead` along the path from there.
  Eigen::Index closest = 0;
  (path.colwise() - p).colwise().squaredNorm().minCoeff(&closest);
  Eigen::Vector2d target = path.col(path.cols() - 1);
  double remaining = lookahead;
  for (Eigen::Index i = closest; i + 1 < path.cols(); ++i) {
    const Eigen::Vector2d a = path.col(i), b = path.col(i + 1);
    const double len = (b - a).norm();
    if (len >= remaining) {
      target = a + (b - a) * (remaining / std::max(len, 1e-12));
      break;
    }
    remaining -= len;
  }
  const Eigen::Vector2d to = target - p;
  const double dist = to.norm();
  const double goal_dist = (path.col(path.cols() - 1) - p).norm();
  if (dist < 1e-6) return {0, 0};
  const double alpha = std::remainder(std::atan2(to.y(), to.x()) - robot.heading, 2.0 * M_PI);
  if (std::abs(alpha) > M_PI / 2) return {0.0, std::copysign(limits.omega_max, alpha)};
  const double v =
      std::min(limits.v_max, limits.v_max * std::min(1.0, goal_dist / lookahead)) * std::cos(alpha);
  const double omega = 2.0 * std::max(v, 0.2) * std::sin(alpha) / std::max(dist, 1e-3);
  return limits.Clamp({v, omega});
}

struct ClRrtStarController::Impl {
  ClRrtStarOptions options;
  const StaticCollisionField* field = nullptr;
  occupancy::MapWorkspace map_ws;
  Eigen::Matrix2Xd pedestrians;  ///< current positions [2 x n]
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  std::shared_ptr<ob::RealVectorStateSpace> space;
  std::shared_ptr<og::SimpleSetup> setup;

  bool Valid(const ob::State* s) const {
    const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
    const double x = v->values[0], y = v->values[1];
    const double r = options.robot_radius + options.pedestrian_radius;
    for (Eigen::Index i = 0; i < pedestrians.cols(); ++i)
      if ((pedestrians.col(i) - Eigen::Vector2d(x, y)).squaredNorm() < r * r) return false;
    // The static check spares a small ball around the robot: a tracker that cut a corner into the
    // epsilon band would otherwise make every plan start invalid and freeze the robot for good.
    if ((Eigen::Vector2d(x, y) - start).squaredNorm() <
        options.start_exemption * options.start_exemption)
      return true;
    return !(field &&
             field->Collides(x, y, options.epsilon, const_cast<occupancy::MapWorkspace*>(&map_ws)));
  }
};

ClRrtStarController::ClRrtStarController(const StaticCollisionField* field,
                                         const Eigen::Vector4d& extent, ClRrtStarOptions options,
                                         std::uint64_t seed)
    : impl_(std::make_unique<Impl>()) {
  const std::string problems = options.Problems();
  FS_THROW_UNLESS(problems.empty(), "CL-RRT* options: ", problems);
  FS_THROW_UNLESS(extent.allFinite() && extent[1] > extent[0] && extent[3] > extent[2],
                  "CL-RRT*: planning extent [", extent.transpose(), "] is empty");
  static std::once_flag once;
  std::call_once(once, [seed] {
    ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
    ompl::RNG::setSeed(seed +
                       1);  // OMPL seeds once per process; later planners draw from it in order
  });
  impl_->options = options;
  impl_->field = field && !field->empty() ? field : nullptr;
  if (impl_->field) impl_->map_ws = impl_->field->MakeWorkspace();
  impl_->space = std::make_shared<ob::RealVectorStateSpace>(2);
  ob::RealVectorBounds bounds(2);
  bounds.setLow(0, extent[0]);
  bounds.setHigh(0, extent[1]);
  bounds.setLow(1, extent[2]);
  bounds.setHigh(1, extent[3]);
  impl_->space->setBounds(bounds);
  impl_->setup = std::make_shared<og::SimpleSetup>(impl_->space);
  Impl* impl = impl_.get();
  impl_->setup->setStateValidityChecker([impl](const ob::State* s) { return impl->Valid(s); });
  const double span =
      std::hypot(extent[1] - extent[0], extent[3] - extent[2]);  // OMPL: fraction of the diagonal
  impl_->setup->getSpaceInformation()->setStateValidityCheckingResolution(options.check_resolution /
                                                                          span);
  impl_->setup->setOptimizationObjective(
      std::make_shared<ob::PathLengthOptimizationObjective>(impl_->setup->getSpaceInformation()));
}

ClRrtStarController::~ClRrtStarController() = default;

ControlOutcome ClRrtStarController::Compute(const NavigationInput& input) {
  ControlOutcome out;
  try {
    Eigen::MatrixXd clean;
    const int n =
        input.past_rows ? CleanObservations(*input.past_rows, &clean, &impl_->pedestrians) : 0;
    impl_->pedestrians.conservativeResize(2, n);  // rows without any finite point were dropped
    impl_->start = input.robot.position();
    const auto& o = impl_->options;
    if ((input.robot.position() - input.goal).norm() <= o.goal_tolerance) {
      out.command = {0, 0};
      return out;
    }
    og::SimpleSetup& ss = *impl_->setup;
    ss.clear();
    auto planner = std::make_shared<og::RRTstar>(ss.getSpaceInformation());
    planner->setRange(o.range);
    ss.setPlanner(planner);
    ob::ScopedState<ob::RealVectorStateSpace> start(impl_->space), goal(impl_->space);
    start[0] = input.robot.x;
    start[1] = input.robot.y;
    goal[0] = input.goal.x();
    goal[1] = input.goal.y();
    ss.setStartAndGoalStates(start, goal, o.goal_tolerance);
    const int cap = o.max_iterations;
    const ob::PlannerTerminationCondition ptc = ob::plannerOrTerminationCondition(
        ob::timedPlannerTerminationCondition(o.budget_s),
        ob::PlannerTerminationCondition(
            [planner, cap] { return planner->numIterations() >= static_cast<unsigned>(cap); }));
    const ob::PlannerStatus status = ss.solve(ptc);
    out.evaluations = static_cast<int>(planner->numIterations());
    const bool exact = status == ob::PlannerStatus::EXACT_SOLUTION;
    const bool approximate = status == ob::PlannerStatus::APPROXIMATE_SOLUTION;
    if (exact || approximate) {
      const og::PathGeometric& g = ss.getSolutionPath();
      path_.resize(2, static_cast<Eigen::Index>(g.getStateCount()));
      for (std::size_t i = 0; i < g.getStateCount(); ++i) {
        const auto* s = g.getState(i)->as<ob::RealVectorStateSpace::StateType>();
        path_.col(static_cast<Eigen::Index>(i)) = Eigen::Vector2d(s->values[0], s->values[1]);
      }
    }
    // A partial path (the tree's node closest to the goal) is followed when it gets the robot at
    // least `min_progress` closer; otherwise nothing useful was found and the robot stays put.
    const bool progress = path_.cols() > 0 && (approximate || exact) &&
                          (input.robot.position() - input.goal).norm() -
                                  (path_.col(path_.cols() - 1) - input.goal).norm() >=
                              o.min_progress;
    if (!(exact || (approximate && progress))) {
      path_.resize(2, 0);
      out.status = ControlStatus::kNoPath;
      out.message = "no plan reaches the goal or makes progress";
      out.command = {0, 0};
      return out;
    }
    const og::PathGeometric& g = ss.getSolutionPath();
    out.cost = g.length();
    out.command = PurePursuit(input.robot, path_, o.lookahead, o.limits);
  } catch (const std::exception& e) {
    path_.resize(2, 0);
    out = ControlOutcome::Stop(ControlStatus::kError, e.what());
  }
  return out;
}

}  // namespace foresight::nav
