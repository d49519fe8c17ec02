#pragma once
/// Training and export of one shape of a diffeomorphic-templates run (LibTorch inside, torch-free
/// header): the imitation transform (models/imitation/flow_net.h) and the Euclideanizing-Flows
/// baseline (eflow_net.h), each by the trainer on the velocity loss of thesis eq. learn_cost,
/// with its own checkpoints; export writes the engines' artifacts from the best checkpoints.

#include <atomic>
#include <string>

#include "training/diffeo/config.h"
#include "training/diffeo/demos.h"

namespace foresight::imitation {

/// Where one shape's files live in a run directory.
struct ShapePaths {
  ShapePaths(std::string run, std::string shape)
      : run_dir(std::move(run)), name(std::move(shape)) {}
  std::string run_dir, name;
  std::string FlowDir() const { return run_dir + "/shapes/" + name + "/flow"; }
  /// Restart r's flow (flow.restarts, flow.alternatives): FlowDir() for r = 0, FlowDir() + "_<r>"
  /// after it.
  std::string FlowDir(int r) const {
    return r == 0 ? FlowDir() : FlowDir() + "_" + std::to_string(r);
  }
  std::string EflowDir() const { return run_dir + "/shapes/" + name + "/eflow"; }
  std::string Template() const { return run_dir + "/models/" + name + ".h5"; }
  std::string Eflow() const { return run_dir + "/models/" + name + ".eflow.h5"; }
};

/// Whether every artifact of the shape exists (a resumed run skips it).
bool ShapeExported(const ExperimentConfig& c, const ShapePaths& paths);
/// Trains the shape's networks (continuing their checkpoints when `resume` and they exist).
/// @return false when interrupted.
bool TrainShape(const ExperimentConfig& c, const PreparedDemos& demos, const ShapePaths& paths,
                bool resume, const std::atomic<bool>* interrupt);
/// Writes the artifacts from the best checkpoints; refuses a flow that is not invertible on the
/// grid and the demonstrations (CheckInvertible with flow.inverse_tolerance), naming the settings.
/// With flow.restarts R > 1 (or flow.alternatives) the flow exported is the invertible restart,
/// of every setting, whose rollouts from the training demonstrations' starts follow them best
/// (mean discrete Frechet distance; training data only), the lowest index on a tie; the artifact
/// carries that restart's flow time and steps.
void ExportShape(const ExperimentConfig& c, const PreparedDemos& demos, const ShapePaths& paths);

}  // namespace foresight::imitation
