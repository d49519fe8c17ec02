#pragma once
/// Pictures of constrained prediction (thesis ch 7, figures "example_opt" and "xyTraj"): one PNG
/// per window with the prior (left) and the optimised distribution (right) over the scene's
/// obstacles: observed track (blue), ground truth (green), sampled trajectories (red), and the
/// Gauss-Hermite abscissae of the main component at each time (orange before, cyan after).

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "datasets/crowd_scenario.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::constrained {

struct WindowPicture {
  Eigen::MatrixX2d past, truth;  ///< [p x 2], [f x 2]
  TrajectoryDistribution prior, optimised;
  double prior_cost = 0, cost = 0;
};

/// Writes `path` (an Error naming it when OpenCV cannot). `times`: the f prediction times (s).
void DrawWindowPicture(const std::string& path, const OccupancyRaster& raster,
                       const WindowPicture& w, const Eigen::VectorXd& times, int order, int samples,
                       std::uint64_t seed);

}  // namespace foresight::constrained
