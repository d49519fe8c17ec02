#include "training/diffeo/plots.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "training/image_io.h"

namespace foresight::imitation {
namespace {

constexpr int kSize = 560;

struct Frame {
  Eigen::Vector2d lo, hi;
  cv::Point At(const Eigen::Vector2d& p) const {
    const double u = (p.x() - lo.x()) / (hi.x() - lo.x()), v = (p.y() - lo.y()) / (hi.y() - lo.y());
    return {static_cast<int>(std::lround(u * (kSize - 1))),
            static_cast<int>(std::lround((1 - v) * (kSize - 1)))};
  }
};

void DrawPaths(cv::Mat* img, const Frame& f, const PathSet& set, const cv::Scalar& colour,
               int width) {
  for (const Eigen::MatrixXd& p : set.paths)
    for (Eigen::Index k = 1; k < p.cols(); ++k)
      cv::line(*img, f.At(p.col(k - 1).head<2>()), f.At(p.col(k).head<2>()), colour, width,
               cv::LINE_AA);
}

void DrawDemos(cv::Mat* img, const Frame& f, const DemoSet& demos) {
  for (const Demonstration& d : demos.demos)
    for (Eigen::Index k = 1; k < d.position.cols(); ++k)
      cv::line(*img, f.At(d.position.col(k - 1).head<2>()), f.At(d.position.col(k).head<2>()),
               cv::Scalar(60, 170, 60), 2, cv::LINE_AA);
}

}  // namespace

void DrawPlanar(const PlanarPicture& pic, const std::string& png) {
  FS_THROW_UNLESS(pic.demos != nullptr, "DrawPlanar: no demonstrations");
  Frame f;
  f.lo = Eigen::Vector2d::Constant(1e300);
  f.hi = -f.lo;
  for (const Demonstration& d : pic.demos->demos) {
    f.lo = f.lo.cwiseMin(d.position.rowwise().minCoeff().head<2>());
    f.hi = f.hi.cwiseMax(d.position.rowwise().maxCoeff().head<2>());
  }
  // A square frame (equal scales on both axes) around the demonstrations, with a margin.
  const double half = 0.5 * (f.hi - f.lo).maxCoeff() * 1.3 + 1e-6;
  const Eigen::Vector2d mid = 0.5 * (f.lo + f.hi);
  f.lo = mid.array() - half;
  f.hi = mid.array() + half;
  const bool obstacle = pic.obstacle_centre.size() == 2;
  cv::Mat left(kSize, kSize, CV_8UC3, cv::Scalar(255, 255, 255));
  // The imitation vector field as unit arrows (direction only; the speed varies a lot).
  if (pic.field) {
    constexpr int kArrows = 22;
    for (int i = 0; i < kArrows; ++i)
      for (int j = 0; j < kArrows; ++j) {
        const Eigen::Vector2d p(f.lo.x() + (f.hi.x() - f.lo.x()) * (i + 0.5) / kArrows,
                                f.lo.y() + (f.hi.y() - f.lo.y()) * (j + 0.5) / kArrows);
        const Eigen::Vector2d v = pic.field(p);
        if (!v.allFinite() || v.norm() < 1e-12) continue;
        const Eigen::Vector2d q = p + v.normalized() * 0.35 * (f.hi - f.lo).minCoeff() / kArrows;
        cv::arrowedLine(left, f.At(p), f.At(q), cv::Scalar(170, 170, 170), 1, cv::LINE_AA, 0, 0.35);
      }
  }
  DrawDemos(&left, f, *pic.demos);
  DrawPaths(&left, f, pic.eflow, cv::Scalar(200, 120, 30), 1);
  DrawPaths(&left, f, pic.rollouts, cv::Scalar(40, 40, 220), 2);
  DrawPaths(&left, f, pic.biased, cv::Scalar(180, 40, 180), 2);
  cv::putText(left, "demos (green), ours (red), EFlow (blue)", {8, 20}, cv::FONT_HERSHEY_SIMPLEX,
              0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::Mat out = left;
  if (obstacle) {
    cv::Mat right(kSize, kSize, CV_8UC3, cv::Scalar(255, 255, 255));
    const cv::Point c = f.At(pic.obstacle_centre);
    const int r = static_cast<int>(pic.obstacle_radius / (f.hi.x() - f.lo.x()) * (kSize - 1));
    cv::circle(right, c, r, cv::Scalar(110, 110, 110), cv::FILLED, cv::LINE_AA);
    DrawDemos(&right, f, *pic.demos);
    DrawPaths(&right, f, pic.eflow_repulsor, cv::Scalar(200, 120, 30), 1);
    DrawPaths(&right, f, pic.avoid, cv::Scalar(40, 40, 220), 2);
    cv::putText(right, "obstacle: ours (red), EFlow + repulsor (blue)", {8, 20},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::hconcat(left, right, out);
  }
  WriteImage(png, out);
}

}  // namespace foresight::imitation
