#pragma once
/// Evaluation of a diffeomorphic-templates run with the torch-free engines (thesis ch 8, tables
/// "Performance, as measured by Frechet Distance and Maximum Collision Distance"):
/// - imitation: rollouts of the exported template from the start of every demonstration (trained
///   on or held out), discrete Frechet distance to that demonstration after arc-length
///   resampling, share reaching the goal, and a grid of starts (stability);
/// - an obstacle on the demonstrations: its occupancy map fitted on samples, the obstacle
///   transform composed by the pull-back, its flow time selected on the map; maximum collision
///   depth (MCD) against the exact obstacle, Frechet distance to the demonstrations;
/// - baselines in the same table: Euclideanizing Flows, EFlow with an overlaid repulsor (gain
///   selected on the map the same way), linear motion to the goal;
/// - optionally a user bias toward a point.
/// 2-D sets are scored in normalised units; task-space sets (the JACO arm) in metres in C-space.
/// Torch-free.

#include <string>
#include <utility>
#include <vector>

#include "training/diffeo/config.h"
#include "training/diffeo/demos.h"

namespace foresight::imitation {

/// Named figures of one shape, in the order they are written to eval.json.
using Scores = std::vector<std::pair<std::string, double>>;

/// Evaluates one prepared shape with its artifacts (template, and EFlow when eflow_path is not
/// empty); draws plots/<name>.png when `plot_dir` is not empty.
Scores EvaluatePlanarShape(const ExperimentConfig& c, const PreparedDemos& demos,
                           const std::string& template_path, const std::string& eflow_path,
                           const std::string& plot_dir);
/// The same for a task-space set on the JACO arm (C-space rollouts, body-ball MCD).
Scores EvaluateTaskSpaceShape(const ExperimentConfig& c, const PreparedDemos& demos,
                              const std::string& template_path, const std::string& eflow_path,
                              const std::string& plot_dir);

/// eval.json: {"shapes": {name: {...}}, "mean": {...}} (mean over shapes of every figure).
std::string EvalJson(const std::vector<std::pair<std::string, Scores>>& shapes);

}  // namespace foresight::imitation
