#pragma once
/// Pictures of navigation runs: the robot paths of every episode over the static map (PNG) and a
/// video of one episode with pedestrians, the robot and sampled predicted futures (OpenCV, MJPG).

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <random>
#include <string>
#include <vector>

#include "training/map_canvas.h"
#include "training/navigation/run.h"

namespace foresight::nav {

class VideoRecorder final : public EpisodeRecorder {
 public:
  /// Opens `path` (an Error naming it when OpenCV cannot write the video).
  VideoRecorder(const std::string& path, const OccupancyRaster& raster, const VideoConfig& config,
                double dt, std::uint64_t seed);
  void Frame(double time, const nav::UnicycleState& robot, const Eigen::Vector2d& goal,
             const std::vector<CrowdAgent>& agents,
             const std::vector<TrajectoryDistribution>* predictions, int num_predictions,
             const Eigen::Matrix2Xd& path_so_far) override;
  int frames() const { return frames_; }

 private:
  MapCanvas canvas_;
  VideoConfig config_;
  cv::VideoWriter writer_;
  std::mt19937_64 rng_;
  Eigen::VectorXd times_;
  Eigen::Matrix<double, Eigen::Dynamic, 2> sample_;
  int frames_ = 0;
};

/// Every episode's path per method (one colour each) over the map, with starts and goals.
void DrawPaths(const std::string& path, const OccupancyRaster& raster,
               const ExperimentConfig& config, const std::vector<EpisodeResult>& results);

}  // namespace foresight::nav
