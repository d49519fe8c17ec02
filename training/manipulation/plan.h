#pragma once
/// The manipulation harness (thesis ch 9, "Experimental Evaluation"): every method of a config
/// (GFCS, the single-attractor geometric fabric, Bi-EST, BIT*, RRT-Connect) over a family of
/// problems, judged by one validity checker at one resolution and one metrics module. Writes
/// DIR/summary.json, DIR/problems.csv and DIR/ee_paths.png. Torch-free.

#include <optional>
#include <string>
#include <vector>

#include "inference/manipulation/gfcs.h"
#include "inference/manipulation/mbm_problem.h"
#include "inference/manipulation/metrics.h"
#include "inference/manipulation/robot_model.h"
#include "inference/manipulation/world.h"
#include "training/manipulation/config.h"
#include "training/run_dir.h"

namespace foresight::manipulation {

/// A plan run directory holds these; `plan` refuses to write into another run's directory.
inline const RunDirectoryRules kRunRules{{"summary.json", "problems.csv"}, false};

/// The config's robot: `builtin`, or a folder (panda.urdf, spheres_vamp.csv, panda.srdf) under the
/// data root.
manipulation::RobotModel LoadExperimentRobot(const ExperimentConfig& config);

/// The config's problems (MotionBenchMaker family range, or synthetic scenes for `robot`).
std::vector<manipulation::ManipulationProblem> LoadExperimentProblems(
    const ExperimentConfig& config, const manipulation::RobotModel& robot);

/// One method on one problem.
struct PlanAttempt {
  std::string method;
  int problem = 0;
  int repeat = 0;      ///< the draw (ExperimentConfig::repeats), 0 for a single run
  std::string status;  ///< solved, or why not (timeout, collision, invalid_path, planner status)
  manipulation::PathMetrics metrics;
  Eigen::Matrix3Xd ee_path;         ///< end-effector positions of the trajectory (empty on failure)
  std::optional<double> gfcs_cost;  ///< GFCS: the best candidate's GFCOP cost (s), solved or not
};

/// GFCS: the fabric work of a method, summed over problems.
struct GfcsWork {
  long long steps = 0;  ///< integration steps of every evaluated candidate
  int stalled = 0;      ///< rollouts ended by the fabric's stall test (fabric.stall_window)
  int restarts = 0;     ///< batches drawn afresh after a batch that reached nothing (gfcs.restart)
};

struct PlanMethodResult {
  std::string method;
  manipulation::MetricSummary summary;
  /// GFCS: how every evaluated candidate ended, summed over problems (summary.json
  /// "candidate_statuses").
  manipulation::RolloutStatusCounts candidate_statuses{};
  /// GFCS: medians over the problems of the whole method time, the world's encoding (learned
  /// sampler) and the sampler's first batch (SGLD for the learned sampler), in s (summary.json
  /// "time_median_s"; medians, so the parts need not add up to the total).
  double median_total_s = 0, median_encode_s = 0, median_sample_s = 0;
  GfcsWork work;  ///< summary.json "integration_steps", "stalled_rollouts", "restarts"
};

struct PlanReport {
  int problems = 0;
  std::vector<int> invalid_problems;  ///< start or goal invalid for this robot model: skipped
  std::vector<PlanMethodResult> methods;
  std::vector<PlanAttempt> attempts;
  int reactivity_trials = 0, reactivity_successes = 0;
};

/// Runs the config's methods on its problems and writes the outputs into `run_dir` (which exists).
/// Never throws from inside a method's run: failures are statuses in the report.
PlanReport RunPlanExperiment(const ExperimentConfig& config, const std::string& run_dir);

}  // namespace foresight::manipulation
