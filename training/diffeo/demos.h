#pragma once
/// The demonstrations of a diffeomorphic-templates run, read, checked, split and normalised as the
/// config says. Torch-free.

#include <string>
#include <vector>

#include "datasets/demonstrations.h"
#include "training/diffeo/config.h"

namespace foresight::imitation {

/// One shape (or task) ready to train on: every demo normalised by the training demos' goal and
/// extent (x_n = (x - offset) * scale, goal at the origin), downsampled as configured.
struct PreparedDemos {
  std::string name;        ///< shape or task name (also the file stem of its artifacts)
  DemoSet demos;           ///< normalised; every demo not in data.excluded, in their original order
  DemoNormalisation norm;  ///< fitted on the training demos
  std::vector<int> train, held_out;  ///< indices into `demos`
  std::vector<int> original;  ///< each demo's index in the data (differs after data.excluded)
  GoalSpread spread;          ///< of the raw demos
};

/// Reads the demonstrations the config names (every LASA shape asked for, one synthetic family,
/// or one task-space task), checks them (CheckDemonstrations with data.goal_tolerance: differing
/// dimensions, NaN, no common goal are Errors naming the set and demo) and prepares them.
std::vector<PreparedDemos> LoadDemos(const ExperimentConfig& c);

/// Positions and velocities [d x n] of the given demos, concatenated.
void StackDemos(const DemoSet& set, const std::vector<int>& ids, Eigen::MatrixXd* positions,
                Eigen::MatrixXd* velocities);

}  // namespace foresight::imitation
