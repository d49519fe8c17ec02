#pragma once
/// Pictures of a diffeomorphic-templates run: the imitation vector field with its rollouts and the
/// demonstrations, and the obstacle panel (composed system, EFlow + repulsor). Torch-free.

#include <Eigen/Core>
#include <functional>
#include <string>

#include "datasets/demonstrations.h"
#include "training/diffeo/eval_common.h"

namespace foresight::imitation {

struct PlanarPicture {
  const DemoSet* demos = nullptr;              ///< normalised demonstrations
  std::function<Vec<2>(const Vec<2>&)> field;  ///< f_i, drawn as arrows
  PathSet rollouts, eflow, avoid, eflow_repulsor, biased;
  Eigen::VectorXd obstacle_centre;  ///< empty: no obstacle
  double obstacle_radius = 0;
};

/// Two panels side by side (imitation | obstacle, when there is one) written to `png`.
void DrawPlanar(const PlanarPicture& picture, const std::string& png);

}  // namespace foresight::imitation
