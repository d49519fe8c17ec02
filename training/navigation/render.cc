#include "training/navigation/render.h"

#include <cmath>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.h"
#include "training/image_io.h"

namespace foresight::nav {

namespace {
const cv::Scalar kRobot(40, 40, 220), kGoal(60, 170, 60), kPedestrian(110, 110, 110),
    kFuture(210, 140, 40);
cv::Scalar MethodColour(const std::string& m) {
  if (m == "span") return {40, 40, 220};
  if (m == "reactive") return {200, 120, 30};
  if (m == "orca") return {170, 60, 170};  // purple (BGR)
  return {40, 160, 40};
}
}  // namespace

VideoRecorder::VideoRecorder(const std::string& path, const OccupancyRaster& raster,
                             const VideoConfig& config, double dt, std::uint64_t seed)
    : canvas_(raster, config.pixels_per_metre), config_(config), rng_(seed) {
  const cv::Mat bg = canvas_.Background();
  writer_.open(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 1.0 / dt, bg.size(), true);
  FS_THROW_UNLESS(writer_.isOpened(), path, ": OpenCV cannot write an MJPG video here");
  times_ = Eigen::VectorXd::LinSpaced(40, 0.1, 4.0);
  sample_.resize(times_.size(), 2);
}

void VideoRecorder::Frame(double time, const nav::UnicycleState& robot, const Eigen::Vector2d& goal,
                          const std::vector<CrowdAgent>& agents,
                          const std::vector<TrajectoryDistribution>* predictions,
                          int num_predictions, const Eigen::Matrix2Xd& path_so_far) {
  cv::Mat img = canvas_.Background();
  if (predictions)
    for (int n = 0; n < num_predictions; ++n)
      for (int s = 0; s < config_.samples; ++s) {
        (*predictions)[static_cast<std::size_t>(n)].SamplePath(times_, &rng_, sample_);
        for (Eigen::Index k = 1; k < sample_.rows(); ++k)
          cv::line(img, canvas_.Pixel(sample_(k - 1, 0), sample_(k - 1, 1)),
                   canvas_.Pixel(sample_(k, 0), sample_(k, 1)), kFuture, 1, cv::LINE_AA);
      }
  for (const CrowdAgent& a : agents)
    if (a.active)
      cv::circle(img, canvas_.Pixel(a.position.x(), a.position.y()), canvas_.Length(a.radius),
                 kPedestrian, 2, cv::LINE_AA);
  for (Eigen::Index i = 1; i < path_so_far.cols(); ++i)
    cv::line(img, canvas_.Pixel(path_so_far(0, i - 1), path_so_far(1, i - 1)),
             canvas_.Pixel(path_so_far(0, i), path_so_far(1, i)), kRobot, 2, cv::LINE_AA);
  cv::drawMarker(img, canvas_.Pixel(goal.x(), goal.y()), kGoal, cv::MARKER_CROSS,
                 canvas_.Length(0.6), 3);
  const cv::Point c = canvas_.Pixel(robot.x, robot.y);
  cv::circle(img, c, canvas_.Length(0.4), kRobot, cv::FILLED, cv::LINE_AA);
  cv::line(img, c,
           canvas_.Pixel(robot.x + 0.6 * std::cos(robot.heading),
                         robot.y + 0.6 * std::sin(robot.heading)),
           cv::Scalar(255, 255, 255), 2, cv::LINE_AA);
  std::ostringstream label;
  label << std::fixed << std::setprecision(1) << "t = " << time << " s";
  cv::putText(img, label.str(), {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  writer_.write(img);
  ++frames_;
}

void DrawPaths(const std::string& path, const OccupancyRaster& raster,
               const ExperimentConfig& config, const std::vector<EpisodeResult>& results) {
  const MapCanvas canvas(
      raster, std::min(40.0, 1200.0 / std::max(raster.extent[1] - raster.extent[0], 1.0)));
  cv::Mat img = canvas.Background();
  for (const EpisodeResult& r : results) {
    const cv::Scalar colour = MethodColour(r.method);
    for (Eigen::Index i = 1; i < r.path.cols(); ++i)
      cv::line(img, canvas.Pixel(r.path(0, i - 1), r.path(1, i - 1)),
               canvas.Pixel(r.path(0, i), r.path(1, i)), colour, 1, cv::LINE_AA);
    if (r.path.cols() > 0) {
      cv::circle(img, canvas.Pixel(r.path(0, 0), r.path(1, 0)), 4, colour, cv::FILLED);
      const Eigen::Index last = r.path.cols() - 1;
      cv::drawMarker(img, canvas.Pixel(r.path(0, last), r.path(1, last)), colour,
                     r.reached ? cv::MARKER_STAR : cv::MARKER_TILTED_CROSS, 10, 1);
    }
  }
  int y = 20;
  for (const std::string& m : config.methods) {
    cv::putText(img, m, {10, y}, cv::FONT_HERSHEY_SIMPLEX, 0.55, MethodColour(m), 2, cv::LINE_AA);
    y += 20;
  }
  WriteImage(path, img);
}

}  // namespace foresight::nav
