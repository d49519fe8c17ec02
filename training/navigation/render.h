#pragma once
/// Pictures of navigation runs: the robot paths of every episode over the static map (PNG) and a
/// video of one episode with pedestrians, the robot and sampled predicted futures (OpenCV, MJPG).

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <random>
#include <string>
#include <vector>

#include "training/navigation/run.h"

namespace foresight {

/// World <-> image of a raster's extent at `pixels_per_metre`.
class MapCanvas {
 public:
  MapCanvas(const OccupancyRaster& raster, double pixels_per_metre);
  cv::Mat Background() const { return background_.clone(); }
  cv::Point Pixel(double x, double y) const;
  int Length(double metres) const {
    return std::max(1, static_cast<int>(std::lround(metres * scale_)));
  }

 private:
  Eigen::Vector4d extent_;
  double scale_;
  cv::Mat background_;
};

class VideoRecorder final : public EpisodeRecorder {
 public:
  /// Opens `path` (an Error naming it when OpenCV cannot write the video).
  VideoRecorder(const std::string& path, const OccupancyRaster& raster,
                const NavigationVideoConfig& config, double dt, std::uint64_t seed);
  void Frame(double time, const nav::UnicycleState& robot, const Eigen::Vector2d& goal,
             const std::vector<CrowdAgent>& agents,
             const std::vector<TrajectoryDistribution>* predictions, int num_predictions,
             const Eigen::Matrix2Xd& path_so_far) override;
  int frames() const { return frames_; }

 private:
  MapCanvas canvas_;
  NavigationVideoConfig config_;
  cv::VideoWriter writer_;
  std::mt19937_64 rng_;
  Eigen::VectorXd times_;
  Eigen::Matrix<double, Eigen::Dynamic, 2> sample_;
  int frames_ = 0;
};

/// Every episode's path per method (one colour each) over the map, with starts and goals.
void DrawPaths(const std::string& path, const OccupancyRaster& raster,
               const NavigationExperimentConfig& config, const std::vector<EpisodeResult>& results);

}  // namespace foresight
