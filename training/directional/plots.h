#pragma once
/// PNG figures of directional maps (OpenCV).

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>

#include "datasets/directional.h"
#include "inference/directional/directional_map.h"
#include "training/directional/config.h"

namespace foresight::directional {

/// Thesis "Generating Trajectories in Space": from `start`, repeatedly sample a heading from
/// p(theta | x_n, y_n, t) (t fixed) and step x_{n+1} = x_n + d (cos theta_n, sin theta_n).
/// @return [steps + 1 x 2] positions (m).
Eigen::Matrix<double, Eigen::Dynamic, 2> GenerateTrajectory(const Map& map,
                                                            const Eigen::Vector2d& start, double t,
                                                            double step, int steps,
                                                            std::mt19937_64* rng);

/// Writes `dir`/directions.png (data points and the means of the mixture components, arrow length
/// proportional to alpha) and `dir`/trajectories.png (generated trajectories from random data
/// points). Panels: the spatiotemporal map at 1/4 and 3/4 of its time range (data within 1/4 of
/// the range of that time), and the spatial map when given.
void PlotMaps(const DirectionalSamples& data, const Map& spatiotemporal, const Map* spatial,
              const EvalConfig& eval, std::uint64_t seed, const std::string& dir);

}  // namespace foresight::directional
