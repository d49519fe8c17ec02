#include "training/otnet/plots.h"

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "training/image_io.h"

namespace foresight::otnet {
namespace {

constexpr int kPanel = 280;  // pixels per panel side
constexpr int kTitle = 18;

cv::Mat DrawPanel(const TrajectoryPanel& p) {
  FS_THROW_UNLESS(p.map != nullptr && p.map->width > 0, "DrawTrajectoryPanels: a panel has no map");
  const BinaryGrid& g = *p.map;
  cv::Mat img(kPanel + kTitle, kPanel, CV_8UC3, cv::Scalar(255, 255, 255));
  const double s = static_cast<double>(kPanel) / std::max(g.width, g.height);
  // Map y grows downwards in the picture as rows do in the text files.
  const auto at = [&](double x, double y) {
    return cv::Point(static_cast<int>(std::lround(x * s)),
                     kTitle + static_cast<int>(std::lround(y * s)));
  };
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c)
      if (g.at(r, c))
        cv::rectangle(img, at(c, r), at(c + 1, r + 1), cv::Scalar(90, 90, 90), cv::FILLED);
  const auto draw = [&](const std::vector<Eigen::MatrixX2d>& set, const cv::Scalar& colour,
                        int width, bool ends) {
    for (const Eigen::MatrixX2d& t : set) {
      for (Eigen::Index k = 1; k < t.rows(); ++k)
        cv::line(img, at(t(k - 1, 0), t(k - 1, 1)), at(t(k, 0), t(k, 1)), colour, width,
                 cv::LINE_AA);
      if (ends && t.rows() > 0)
        cv::circle(img, at(t(t.rows() - 1, 0), t(t.rows() - 1, 1)), 3, colour, cv::FILLED,
                   cv::LINE_AA);
    }
  };
  draw(p.truth, cv::Scalar(220, 150, 60), 1, false);
  draw(p.colliding, cv::Scalar(40, 160, 250), 1, true);
  draw(p.generated, cv::Scalar(40, 40, 220), 1, true);
  if (p.has_start)
    cv::circle(img, at(p.start.x(), p.start.y()), 5, cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(img, p.title, {4, 13}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return img;
}

}  // namespace

void DrawTrajectoryPanels(const std::vector<std::vector<TrajectoryPanel>>& rows,
                          const std::string& png) {
  FS_THROW_UNLESS(!rows.empty(), "DrawTrajectoryPanels: nothing to draw");
  std::size_t columns = 0;
  for (const auto& r : rows) columns = std::max(columns, r.size());
  FS_THROW_UNLESS(columns > 0, "DrawTrajectoryPanels: nothing to draw");
  const int w = static_cast<int>(columns) * (kPanel + 4),
            h = static_cast<int>(rows.size()) * (kPanel + kTitle + 4);
  cv::Mat out(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < rows[i].size(); ++j) {
      const cv::Mat panel = DrawPanel(rows[i][j]);
      panel.copyTo(
          out(cv::Rect(static_cast<int>(j) * (kPanel + 4),
                       static_cast<int>(i) * (kPanel + kTitle + 4), kPanel, kPanel + kTitle)));
    }
  WriteImage(png, out);
}

}  // namespace foresight::otnet
