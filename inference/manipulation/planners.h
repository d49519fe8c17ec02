#pragma once
/// Sampling-based baselines of thesis ch 9 through OMPL: Bi-EST, BIT* (1.2 s and 6 s budgets in the
/// thesis) and RRT-Connect, all over the same validity callback and the same interpolation
/// resolution as the fabrics. OMPL (and Boost) stay inside planners.cc.
///
/// Planning is in the joint box [lower, upper] with the Euclidean metric; a straight segment
/// between two states is valid when the states at fractions j / n, j = 1..n, n = ceil(|q_b - q_a| /
/// resolution_rad), all pass `is_valid` (OMPL's discrete motion validator with longest valid
/// segment fraction resolution_rad / (box diagonal)), so consecutive checked states are at most
/// resolution_rad apart. The result is a geometric path (waypoints, no timing); metrics.h
/// TimeParameterise times it for the smoothness metrics.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>

#include "core/config.h"
#include "inference/manipulation/joint_types.h"

namespace foresight::manipulation {

enum class PlannerKind {
  kBiEst,       ///< bi-directional expansive space trees; stops at the first solution
  kBitStar,     ///< batch informed trees (asymptotically optimal); runs for the whole budget
  kRrtConnect,  ///< bi-directional RRT; stops at the first solution
};

/// {kBiEst, "biest"}, {kBitStar, "bitstar"}, {kRrtConnect, "rrtconnect"} (config and CLI names).
const config::EnumNames<PlannerKind>& PlannerKindNames();
const char* PlannerName(PlannerKind kind);
/// The kind named `name` (one of PlannerKindNames()); any other name is an Error listing them.
PlannerKind ParsePlannerKind(const std::string& name);

struct PlannerOptions {
  /// Wall-clock planning budget (s). BIT* uses all of it and returns its best path; Bi-EST and
  /// RRT-Connect return at their first solution or fail when the budget ends. OMPL checks the
  /// budget between steps: BIT* overran 0.2 s budgets by up to 0.1 s on the test problem.
  double time_budget_s = 1.0;
  /// Largest C-space step (rad, Euclidean over the 7 joints) between checked states on a segment;
  /// use the same value as the fabric rollout / validity interpolation.
  double resolution_rad = 0.05;
  /// Shorten the solution afterwards with OMPL's PathSimplifier (reduceVertices,
  /// collapseCloseVertices, shortcutPath; no B-spline smoothing, which adds waypoints and so stops
  /// under TimeParameterise). Simplification time counts in planning_time_s, not the budget.
  bool simplify = false;
  /// Seed of OMPL's random number generators for this call (>= 1: OMPL rejects 0); see Plan.
  std::uint32_t seed = 1;
  /// Bi-EST and RRT-Connect: longest tree extension (rad); 0 = OMPL's default, 0.2 x box diagonal.
  double range_rad = 0;
  /// BIT*: samples per batch (OMPL's default 100).
  int bitstar_samples_per_batch = 100;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("time_budget_s", &time_budget_s, Range::Positive(), "planning budget (s)");
    a->Visit("resolution_rad", &resolution_rad, Range::Positive(),
             "largest C-space step between checked states on a segment (rad, Euclidean)");
    a->Visit("simplify", &simplify, Range::Any(), "shortcut the solution (no smoothing)");
    a->Visit("seed", &seed, Range::AtLeast(1), "OMPL random seed for this call");
    a->Visit("range_rad", &range_rad, Range::NonNegative(),
             "Bi-EST / RRT-Connect extension length (rad); 0 = OMPL default");
    a->Visit("bitstar_samples_per_batch", &bitstar_samples_per_batch, Range::AtLeast(1),
             "BIT* samples per batch");
  }
  /// True when every field is in range; otherwise false with the problems in `error` (if given).
  bool IsValid(std::string* error = nullptr) const;
};

enum class PlannerStatus {
  kSolved,        ///< an exact path from start to goal
  kApproximate,   ///< only a path ending near the goal: a failure (no waypoints returned)
  kTimeout,       ///< nothing found within the budget
  kInvalidStart,  ///< start outside the joint box, non-finite, or rejected by is_valid
  kInvalidGoal,   ///< goal outside the joint box, non-finite, or rejected by is_valid
  kError,         ///< OMPL or is_valid threw, or OMPL reported a crash; see message
};
const char* ToString(PlannerStatus status);

struct PlannerResult {
  PlannerStatus status = PlannerStatus::kError;
  std::string message;         ///< why, when not solved
  Eigen::MatrixXd waypoints;   ///< [kDof x K] joint angles (rad), start first, goal last; K = 0
                               ///< unless solved
  double planning_time_s = 0;  ///< wall clock of the whole call (setup, planning, simplification)
  int collision_checks = 0;    ///< calls of is_valid (states and interpolated segment states)

  bool solved() const { return status == PlannerStatus::kSolved; }
  /// One line: "solved, 5 waypoints, 0.012 s, 1234 checks" (plus ": message" when set).
  std::string BriefReport() const;
};

/// Plans a collision-free joint path from `start` to `goal`.
/// @param start, goal [kDof] joint angles (rad).
/// @param lower, upper [kDof] joint limits (rad), lower < upper, finite (else Error).
/// @param is_valid true when a configuration is collision free (and within whatever limits the
///        caller enforces); called from this thread only. If it throws, the result is kError.
/// @param options must satisfy IsValid (else Error).
/// Expected outcomes (no path, invalid start or goal, an exception inside OMPL) are statuses;
/// nothing thrown by OMPL escapes.
///
/// Process-wide OMPL state: the first call sets OMPL's console log level to LOG_NONE (results carry
/// their own message). Each call re-seeds OMPL's seed generator with options.seed before creating
/// its planner, so every random generator of that planner derives from the seed: Bi-EST and
/// RRT-Connect give identical paths for identical calls, and a BIT* run with a longer budget
/// continues the same sequence as with a shorter one. OMPL's documentation allows setSeed only
/// before the first generator exists and logs an error otherwise, but OMPL 1.5 still re-seeds the
/// generator of future seeds; planners_test checks this. Calls overlapping in time (several
/// threads) share that generator, so their seeds interleave and are not reproducible.
PlannerResult Plan(PlannerKind kind, const JointVector& start, const JointVector& goal,
                   const JointVector& lower, const JointVector& upper,
                   const std::function<bool(const JointVector&)>& is_valid,
                   const PlannerOptions& options);

}  // namespace foresight::manipulation
