#include "inference/manipulation/planners.h"

#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/est/BiEST.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <mutex>
#include <sstream>

#include "core/error.h"

namespace foresight::manipulation {

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

JointVector ToJoints(const ob::State* s) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  JointVector q;
  for (int j = 0; j < kDof; ++j) q(j) = v->values[j];
  return q;
}

bool WithinBounds(const JointVector& q, const JointVector& lower, const JointVector& upper) {
  return q.allFinite() && (q.array() >= lower.array()).all() && (q.array() <= upper.array()).all();
}

std::string Row(const JointVector& q) {
  std::ostringstream os;
  os << "[" << q.transpose() << "]";
  return os.str();
}

ob::PlannerPtr MakePlanner(PlannerKind kind, const ob::SpaceInformationPtr& si,
                           const PlannerOptions& options) {
  switch (kind) {
    case PlannerKind::kBiEst: {
      auto p = std::make_shared<og::BiEST>(si);
      if (options.range_rad > 0) p->setRange(options.range_rad);
      return p;
    }
    case PlannerKind::kBitStar: {
      auto p = std::make_shared<og::BITstar>(si);
      p->setSamplesPerBatch(static_cast<unsigned int>(options.bitstar_samples_per_batch));
      return p;
    }
    case PlannerKind::kRrtConnect: {
      auto p = std::make_shared<og::RRTConnect>(si);
      if (options.range_rad > 0) p->setRange(options.range_rad);
      return p;
    }
  }
  Fail("Plan: unknown planner kind ", static_cast<int>(kind));
}

}  // namespace

const config::EnumNames<PlannerKind>& PlannerKindNames() {
  static const config::EnumNames<PlannerKind> names = {{PlannerKind::kBiEst, "biest"},
                                                       {PlannerKind::kBitStar, "bitstar"},
                                                       {PlannerKind::kRrtConnect, "rrtconnect"}};
  return names;
}

const char* PlannerName(PlannerKind kind) {
  for (const auto& [k, name] : PlannerKindNames())
    if (k == kind) return name;
  return "unknown";
}

PlannerKind ParsePlannerKind(const std::string& name) {
  std::string known;
  for (const auto& [k, n] : PlannerKindNames()) {
    if (name == n) return k;
    known += known.empty() ? n : std::string(", ") + n;
  }
  Fail("unknown planner '", name, "'; expected one of: ", known);
}

bool PlannerOptions::IsValid(std::string* error) const {
  std::ostringstream e;
  if (!(std::isfinite(time_budget_s) && time_budget_s > 0))
    e << "time_budget_s = " << time_budget_s << " must be finite and > 0; ";
  if (!(std::isfinite(resolution_rad) && resolution_rad > 0))
    e << "resolution_rad = " << resolution_rad << " must be finite and > 0; ";
  if (seed < 1) e << "seed = " << seed << " must be >= 1 (OMPL ignores seed 0); ";
  if (!(std::isfinite(range_rad) && range_rad >= 0))
    e << "range_rad = " << range_rad << " must be finite and >= 0; ";
  if (bitstar_samples_per_batch < 1)
    e << "bitstar_samples_per_batch = " << bitstar_samples_per_batch << " must be >= 1; ";
  const std::string problems = e.str();
  if (error) *error = problems;
  return problems.empty();
}

const char* ToString(PlannerStatus status) {
  switch (status) {
    case PlannerStatus::kSolved:
      return "solved";
    case PlannerStatus::kApproximate:
      return "approximate";
    case PlannerStatus::kTimeout:
      return "timeout";
    case PlannerStatus::kInvalidStart:
      return "invalid_start";
    case PlannerStatus::kInvalidGoal:
      return "invalid_goal";
    case PlannerStatus::kError:
      return "error";
  }
  return "unknown";
}

std::string PlannerResult::BriefReport() const {
  std::ostringstream os;
  os << ToString(status) << ", " << waypoints.cols() << " waypoints, " << std::fixed
     << std::setprecision(3) << planning_time_s << " s, " << collision_checks << " checks";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

PlannerResult Plan(PlannerKind kind, const JointVector& start, const JointVector& goal,
                   const JointVector& lower, const JointVector& upper,
                   const std::function<bool(const JointVector&)>& is_valid,
                   const PlannerOptions& options) {
  std::string problems;
  FS_THROW_UNLESS(options.IsValid(&problems), "Plan: planner options: ", problems);
  FS_THROW_UNLESS(static_cast<bool>(is_valid), "Plan: no validity function given");
  FS_THROW_UNLESS(lower.allFinite() && upper.allFinite() && (lower.array() < upper.array()).all(),
                  "Plan: joint limits lower ", Row(lower), " upper ", Row(upper),
                  " must be finite with lower < upper");
  const auto begin = std::chrono::steady_clock::now();
  PlannerResult out;
  out.waypoints.resize(kDof, 0);
  const auto finish = [&](PlannerStatus status, std::string message) {
    out.status = status;
    out.message = std::move(message);
    out.planning_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    return out;
  };
  int checks = 0;
  const auto counted = [&](const JointVector& q) {
    ++checks;
    return is_valid(q);
  };
  try {
    // The end states first: clearer reasons than OMPL's, and no OMPL set-up for hopeless problems.
    if (!WithinBounds(start, lower, upper)) {
      out.collision_checks = checks;
      return finish(PlannerStatus::kInvalidStart,
                    "start " + Row(start) + " is outside the joint limits or not finite");
    }
    if (!counted(start)) {
      out.collision_checks = checks;
      return finish(PlannerStatus::kInvalidStart, "start " + Row(start) + " is not valid");
    }
    if (!WithinBounds(goal, lower, upper)) {
      out.collision_checks = checks;
      return finish(PlannerStatus::kInvalidGoal,
                    "goal " + Row(goal) + " is outside the joint limits or not finite");
    }
    if (!counted(goal)) {
      out.collision_checks = checks;
      return finish(PlannerStatus::kInvalidGoal, "goal " + Row(goal) + " is not valid");
    }

    static std::once_flag quiet;
    std::call_once(quiet, [] { ompl::msg::setLogLevel(ompl::msg::LOG_NONE); });
    // Before any generator of this call exists (see Plan's documentation in planners.h).
    ompl::RNG::setSeed(options.seed);

    auto space = std::make_shared<ob::RealVectorStateSpace>(kDof);
    ob::RealVectorBounds bounds(kDof);
    for (int j = 0; j < kDof; ++j) {
      bounds.setLow(static_cast<unsigned int>(j), lower(j));
      bounds.setHigh(static_cast<unsigned int>(j), upper(j));
    }
    space->setBounds(bounds);
    // OMPL's resolution is a fraction of the box diagonal: convert the absolute step.
    space->setLongestValidSegmentFraction(options.resolution_rad / space->getMaximumExtent());
    auto si = std::make_shared<ob::SpaceInformation>(space);
    // An exception must not cross OMPL's solve (its planners leak the states they hold then): the
    // first one is kept, the state counts as invalid, and the termination condition stops the
    // planner, which returns normally.
    std::atomic<bool> check_failed{false};
    std::string check_error;
    si->setStateValidityChecker([&](const ob::State* st) {
      if (check_failed) return false;
      try {
        return counted(ToJoints(st));
      } catch (const std::exception& e) {
        check_error = e.what();
      } catch (...) {
        check_error = "unknown exception";
      }
      check_failed = true;
      return false;
    });
    si->setup();

    auto pdef = std::make_shared<ob::ProblemDefinition>(si);
    ob::ScopedState<ob::RealVectorStateSpace> s(space), g(space);
    for (int j = 0; j < kDof; ++j) {
      s[static_cast<unsigned int>(j)] = start(j);
      g[static_cast<unsigned int>(j)] = goal(j);
    }
    pdef->setStartAndGoalStates(s, g);
    // A cost threshold no path meets, so BIT* never stops early on "good enough".
    auto objective = std::make_shared<ob::PathLengthOptimizationObjective>(si);
    objective->setCostThreshold(ob::Cost(0.0));
    pdef->setOptimizationObjective(objective);

    const ob::PlannerPtr planner = MakePlanner(kind, si, options);
    planner->setProblemDefinition(pdef);
    planner->setup();
    const ob::PlannerStatus status = planner->solve(ob::plannerOrTerminationCondition(
        ob::timedPlannerTerminationCondition(options.time_budget_s),
        ob::PlannerTerminationCondition([&check_failed] { return check_failed.load(); })));
    out.collision_checks = checks;
    const auto failed_check = [&] {
      out.waypoints.resize(kDof, 0);
      return finish(PlannerStatus::kError, "planning failed: " + check_error);
    };
    if (check_failed) return failed_check();
    switch (ob::PlannerStatus::StatusType(status)) {
      case ob::PlannerStatus::EXACT_SOLUTION:
        break;
      case ob::PlannerStatus::APPROXIMATE_SOLUTION:
        return finish(PlannerStatus::kApproximate,
                      "only an approximate solution (distance to goal " +
                          std::to_string(pdef->getSolutionDifference()) + ")");
      case ob::PlannerStatus::TIMEOUT:
        return finish(PlannerStatus::kTimeout,
                      "no solution within " + std::to_string(options.time_budget_s) + " s");
      case ob::PlannerStatus::INVALID_START:
        return finish(PlannerStatus::kInvalidStart, "OMPL: invalid start");
      case ob::PlannerStatus::INVALID_GOAL:
        return finish(PlannerStatus::kInvalidGoal, "OMPL: invalid goal");
      default:
        return finish(PlannerStatus::kError, std::string("OMPL: ") + status.asString());
    }
    const ob::PathPtr solution = pdef->getSolutionPath();
    if (!solution || !pdef->hasExactSolution())
      return finish(PlannerStatus::kError, "OMPL reported an exact solution but holds none");
    og::PathGeometric path(*solution->as<og::PathGeometric>());
    if (options.simplify) {
      og::PathSimplifier simplifier(si);
      simplifier.reduceVertices(path);
      simplifier.collapseCloseVertices(path);
      simplifier.shortcutPath(path);
      if (check_failed) return failed_check();
    }
    out.collision_checks = checks;
    out.waypoints.resize(kDof, static_cast<Eigen::Index>(path.getStateCount()));
    for (std::size_t i = 0; i < path.getStateCount(); ++i)
      out.waypoints.col(static_cast<Eigen::Index>(i)) = ToJoints(path.getState(i));
    return finish(PlannerStatus::kSolved, "");
  } catch (const std::exception& e) {
    out.collision_checks = checks;
    out.waypoints.resize(kDof, 0);
    return finish(PlannerStatus::kError, std::string("planning failed: ") + e.what());
  } catch (...) {
    out.collision_checks = checks;
    out.waypoints.resize(kDof, 0);
    return finish(PlannerStatus::kError, "planning failed: unknown exception");
  }
}

}  // namespace foresight::manipulation
