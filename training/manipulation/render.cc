#include "training/manipulation/render.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "training/image_io.h"

namespace foresight::manipulation {
namespace {

constexpr int kPanel = 420;  // px, square panel
constexpr int kMargin = 46;  // px, room for tick labels
constexpr int kLegend = 28;  // px per legend row

const cv::Scalar kColours[] = {{40, 40, 220},  {40, 160, 40}, {220, 120, 20}, {170, 40, 170},
                               {20, 170, 200}, {120, 120, 0}, {0, 110, 230},  {90, 60, 160}};

/// Axis-aligned extent of the world and the paths in the plane (a, b) of the coordinates.
struct Extent {
  double a0 = 1e9, a1 = -1e9, b0 = 1e9, b1 = -1e9;
  void Add(double a, double b) {
    a0 = std::min(a0, a);
    a1 = std::max(a1, a);
    b0 = std::min(b0, b);
    b1 = std::max(b1, b);
  }
};

/// Points on an obstacle's surface (corners of boxes, rims of cylinders) in world coordinates.
std::vector<Eigen::Vector3d> OutlinePoints(const manipulation::Obstacle& o) {
  std::vector<Eigen::Vector3d> pts;
  if (o.is_box()) {
    const auto& b = o.box();
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d s((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
      pts.push_back(b.X_WB * Eigen::Vector3d(s.cwiseProduct(b.half_size)));
    }
  } else {
    const auto& c = o.cylinder();
    for (int i = 0; i < 24; ++i) {
      const double t = 2 * M_PI * i / 24;
      for (double z : {-c.half_height, c.half_height})
        pts.push_back(c.X_WC * Eigen::Vector3d(c.radius * std::cos(t), c.radius * std::sin(t), z));
    }
  }
  return pts;
}

void DrawPanel(cv::Mat* image, cv::Point origin, const PlanProblemPicture& picture, int a, int b,
               const char* title) {
  const char* names = "xyz";
  Extent e;
  for (const auto& o : picture.world->obstacles())
    for (const Eigen::Vector3d& p : OutlinePoints(o)) e.Add(p[a], p[b]);
  for (const auto& [name, path] : picture.paths)
    for (Eigen::Index i = 0; i < path.cols(); ++i) e.Add(path(a, i), path(b, i));
  if (e.a0 > e.a1) e = Extent{-1, 1, -1, 1};
  const double span = std::max({e.a1 - e.a0, e.b1 - e.b0, 0.2}) * 1.08;
  const double ca = 0.5 * (e.a0 + e.a1), cb = 0.5 * (e.b0 + e.b1);
  const double scale = (kPanel - 2 * kMargin) / span;
  auto px = [&](double u, double v) {
    return cv::Point(origin.x + kMargin + static_cast<int>((u - ca + span / 2) * scale),
                     origin.y + kPanel - kMargin - static_cast<int>((v - cb + span / 2) * scale));
  };
  // Axes with ticks every 0.2 m (0.5 m for large extents), labelled in metres.
  const double tick = span > 2.5 ? 0.5 : 0.2;
  const cv::Scalar axis(90, 90, 90);
  cv::rectangle(*image, px(ca - span / 2, cb - span / 2), px(ca + span / 2, cb + span / 2), axis,
                1);
  for (double u = std::ceil((ca - span / 2) / tick) * tick; u <= ca + span / 2; u += tick) {
    const cv::Point p = px(u, cb - span / 2);
    cv::line(*image, p, p + cv::Point(0, 5), axis, 1);
    cv::putText(*image, cv::format("%.1f", u), p + cv::Point(-12, 18), cv::FONT_HERSHEY_SIMPLEX,
                0.35, axis, 1, cv::LINE_AA);
  }
  for (double v = std::ceil((cb - span / 2) / tick) * tick; v <= cb + span / 2; v += tick) {
    const cv::Point p = px(ca - span / 2, v);
    cv::line(*image, p, p - cv::Point(5, 0), axis, 1);
    cv::putText(*image, cv::format("%.1f", v), p + cv::Point(-38, 4), cv::FONT_HERSHEY_SIMPLEX,
                0.35, axis, 1, cv::LINE_AA);
  }
  cv::putText(
      *image, cv::format("problem %d, %s (%c-%c, m)", picture.problem, title, names[a], names[b]),
      origin + cv::Point(kMargin, 20), cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
  // Obstacles: filled convex hull of their projected outline.
  for (const auto& o : picture.world->obstacles()) {
    std::vector<cv::Point> pts, hull;
    for (const Eigen::Vector3d& p : OutlinePoints(o)) pts.push_back(px(p[a], p[b]));
    cv::convexHull(pts, hull);
    cv::fillConvexPoly(*image, hull, {205, 205, 205}, cv::LINE_AA);
    cv::polylines(*image, hull, true, {150, 150, 150}, 1, cv::LINE_AA);
  }
  for (std::size_t m = 0; m < picture.paths.size(); ++m) {
    const Eigen::Matrix3Xd& path = picture.paths[m].second;
    const cv::Scalar colour = kColours[m % (sizeof(kColours) / sizeof(kColours[0]))];
    for (Eigen::Index i = 1; i < path.cols(); ++i)
      cv::line(*image, px(path(a, i - 1), path(b, i - 1)), px(path(a, i), path(b, i)), colour, 2,
               cv::LINE_AA);
    if (path.cols() > 0) {
      cv::circle(*image, px(path(a, 0), path(b, 0)), 5, {200, 200, 0}, cv::FILLED, cv::LINE_AA);
      cv::circle(*image, px(path(a, path.cols() - 1), path(b, path.cols() - 1)), 5, {200, 0, 200},
                 cv::FILLED, cv::LINE_AA);
    }
  }
}

}  // namespace

void RenderEndEffectorPaths(const std::string& path,
                            const std::vector<PlanProblemPicture>& pictures) {
  std::size_t methods = 0;
  for (const auto& p : pictures) methods = std::max(methods, p.paths.size());
  const int legend_rows = static_cast<int>(methods) + 1;
  const int rows = static_cast<int>(pictures.size());
  cv::Mat image(rows * kPanel + legend_rows * kLegend + 10, 2 * kPanel, CV_8UC3,
                cv::Scalar(255, 255, 255));
  for (int r = 0; r < rows; ++r) {
    DrawPanel(&image, {0, r * kPanel}, pictures[static_cast<std::size_t>(r)], 0, 1, "top view");
    DrawPanel(&image, {kPanel, r * kPanel}, pictures[static_cast<std::size_t>(r)], 0, 2,
              "side view");
  }
  // Legend: methods (colour; "failed on problems ..." when a path is missing), start and goal.
  int y = rows * kPanel + kLegend / 2 + 4;
  for (std::size_t m = 0; m < methods; ++m, y += kLegend) {
    std::string name, failed;
    for (const auto& p : pictures) {
      if (m >= p.paths.size()) continue;
      name = p.paths[m].first;
      if (p.paths[m].second.cols() == 0)
        failed += (failed.empty() ? "" : ", ") + std::to_string(p.problem);
    }
    const cv::Scalar colour = kColours[m % (sizeof(kColours) / sizeof(kColours[0]))];
    cv::line(image, {kMargin, y}, {kMargin + 30, y}, colour, 3, cv::LINE_AA);
    cv::putText(image, name + (failed.empty() ? "" : "  (no path on problem " + failed + ")"),
                {kMargin + 40, y + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
  }
  cv::circle(image, {kMargin + 15, y}, 5, {200, 200, 0}, cv::FILLED, cv::LINE_AA);
  cv::putText(image, "start", {kMargin + 40, y + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1,
              cv::LINE_AA);
  cv::circle(image, {kMargin + 115, y}, 5, {200, 0, 200}, cv::FILLED, cv::LINE_AA);
  cv::putText(image, "goal   (grey: obstacles, projected)", {kMargin + 140, y + 5},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
  WriteImage(path, image);
}

}  // namespace foresight::manipulation
