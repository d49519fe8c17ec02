#include "training/constrained/plots.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>

#include "core/error.h"
#include "inference/constrained/gauss_hermite.h"
#include "training/image_io.h"
#include "training/map_canvas.h"

namespace foresight::constrained {
namespace {

const cv::Scalar kPast(200, 80, 30), kTruth(40, 160, 40), kSample(60, 60, 220),
    kBefore(0, 140, 255), kAfter(220, 200, 0);

/// The raster cropped to the window's neighbourhood (so a large room still shows detail).
OccupancyRaster Crop(const OccupancyRaster& r, const WindowPicture& w) {
  Eigen::Vector2d lo = w.past.colwise().minCoeff().transpose().cwiseMin(
                      w.truth.colwise().minCoeff().transpose()),
                  hi = w.past.colwise().maxCoeff().transpose().cwiseMax(
                      w.truth.colwise().maxCoeff().transpose());
  const double pad = std::max(3.0, 0.5 * (hi - lo).maxCoeff());
  OccupancyRaster out;
  out.resolution = r.resolution;
  const double x0 = std::max(r.extent[0], lo.x() - pad), x1 = std::min(r.extent[1], hi.x() + pad);
  const double y0 = std::max(r.extent[2], lo.y() - pad), y1 = std::min(r.extent[3], hi.y() + pad);
  const int c0 = std::clamp(static_cast<int>((x0 - r.extent[0]) / r.resolution), 0,
                            static_cast<int>(r.cells.cols()) - 1);
  const int c1 = std::clamp(static_cast<int>(std::ceil((x1 - r.extent[0]) / r.resolution)), c0 + 1,
                            static_cast<int>(r.cells.cols()));
  const int r0 = std::clamp(static_cast<int>((r.extent[3] - y1) / r.resolution), 0,
                            static_cast<int>(r.cells.rows()) - 1);
  const int r1 = std::clamp(static_cast<int>(std::ceil((r.extent[3] - y0) / r.resolution)), r0 + 1,
                            static_cast<int>(r.cells.rows()));
  out.cells = r.cells.block(r0, c0, r1 - r0, c1 - c0);
  out.extent << r.extent[0] + c0 * r.resolution, r.extent[0] + c1 * r.resolution,
      r.extent[3] - r1 * r.resolution, r.extent[3] - r0 * r.resolution;
  return out;
}

void Polyline(cv::Mat* img, const MapCanvas& canvas, const Eigen::MatrixX2d& pts,
              const cv::Scalar& colour, int thickness) {
  for (Eigen::Index k = 1; k < pts.rows(); ++k)
    cv::line(*img, canvas.Pixel(pts(k - 1, 0), pts(k - 1, 1)), canvas.Pixel(pts(k, 0), pts(k, 1)),
             colour, thickness, cv::LINE_AA);
}

cv::Mat Panel(const OccupancyRaster& raster, double ppm, const WindowPicture& w,
              const TrajectoryDistribution& d, const Eigen::VectorXd& times, int order, int samples,
              std::uint64_t seed, const cv::Scalar& abscissa_colour, const std::string& label) {
  const MapCanvas canvas(raster, ppm);
  cv::Mat img = canvas.Background();
  std::mt19937_64 rng(seed);
  Eigen::Matrix<double, Eigen::Dynamic, 2> path(times.size(), 2);
  for (int s = 0; s < samples; ++s) {
    d.SamplePath(times, &rng, path);
    Eigen::MatrixX2d full(path.rows() + 1, 2);
    full.row(0) = w.past.row(w.past.rows() - 1);
    full.bottomRows(path.rows()) = path;
    Polyline(&img, canvas, full, kSample, 1);
  }
  int main = 0;
  for (int r = 1; r < d.components(); ++r)
    if (d.alpha(r) > d.alpha(main)) main = r;
  const StandardNormalRule2 rule = StandardNormalRule(order);
  for (Eigen::Index k = 0; k < times.size(); ++k) {
    Eigen::Vector2d mu;
    Eigen::Matrix2d cov;
    d.Position(times[k], main, &mu, &cov);
    const Eigen::Matrix2d l = Eigen::LLT<Eigen::Matrix2d>(cov).matrixL();
    for (int q = 0; q < rule.size(); ++q) {
      const Eigen::Vector2d x = mu + l * rule.points.col(q);
      cv::circle(img, canvas.Pixel(x.x(), x.y()), 2, abscissa_colour, cv::FILLED, cv::LINE_AA);
    }
  }
  Polyline(&img, canvas, w.past, kPast, 2);
  Eigen::MatrixX2d truth(w.truth.rows() + 1, 2);
  truth.row(0) = w.past.row(w.past.rows() - 1);
  truth.bottomRows(w.truth.rows()) = w.truth;
  Polyline(&img, canvas, truth, kTruth, 2);
  cv::putText(img, label, {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return img;
}

}  // namespace

void DrawWindowPicture(const std::string& path, const OccupancyRaster& raster,
                       const WindowPicture& w, const Eigen::VectorXd& times, int order, int samples,
                       std::uint64_t seed) {
  const OccupancyRaster crop = Crop(raster, w);
  const double width = std::max(crop.extent[1] - crop.extent[0], crop.extent[3] - crop.extent[2]);
  const double ppm = std::min(80.0, 600.0 / std::max(width, 1e-3));
  std::ostringstream before, after;
  before << std::fixed << std::setprecision(3) << "prior  C = " << w.prior_cost;
  after << std::fixed << std::setprecision(3) << "optimised  C = " << w.cost;
  const cv::Mat left =
      Panel(crop, ppm, w, w.prior, times, order, samples, seed, kBefore, before.str());
  const cv::Mat right =
      Panel(crop, ppm, w, w.optimised, times, order, samples, seed, kAfter, after.str());
  cv::Mat both;
  cv::hconcat(
      std::vector<cv::Mat>{left, cv::Mat(left.rows, 6, CV_8UC3, cv::Scalar(0, 0, 0)), right}, both);
  WriteImage(path, both);
}

}  // namespace foresight::constrained
