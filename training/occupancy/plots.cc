#include "training/occupancy/plots.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "training/image_io.h"

namespace foresight::occupancy {

void WriteMapPanels(const std::vector<MapPanel>& panels, double resolution,
                    const std::string& png_path) {
  FS_THROW_UNLESS(!panels.empty(), "map plot: no maps");
  const Eigen::Vector4d e = panels[0].map->Extent();
  const int w = std::max(1, static_cast<int>(std::ceil((e[1] - e[0]) / resolution)));
  const int h = std::max(1, static_cast<int>(std::ceil((e[3] - e[2]) / resolution)));
  FS_THROW_UNLESS(static_cast<double>(w) * h <= 4e7, "map plot: ", w, " x ", h,
                  " pixels is too large; raise eval.plot_resolution");
  constexpr int kTitle = 24;
  cv::Mat canvas(2 * (h + kTitle), static_cast<int>(panels.size()) * (w + 4), CV_8UC3,
                 cv::Scalar(255, 255, 255));
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const Map& map = *panels[k].map;
    MapWorkspace ws = map.MakeWorkspace();
    cv::Mat prob(h, w, CV_8UC1), var(h, w, CV_8UC1);
    for (int r = 0; r < h; ++r) {
      const double y = e[3] - (r + 0.5) * resolution;  // image rows go down, y up
      for (int col = 0; col < w; ++col) {
        const double x = e[0] + (col + 0.5) * resolution;
        const QueryResult q = map.Query(x, y, &ws);
        prob.at<std::uint8_t>(r, col) =
            static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - q.probability)));
        // log10 variance from 1e-3 to 1e4 onto 0..255
        const double lv = std::log10(std::max(q.variance, 1e-3));
        var.at<std::uint8_t>(r, col) =
            static_cast<std::uint8_t>(std::clamp((lv + 3.0) / 7.0, 0.0, 1.0) * 255.0);
      }
    }
    cv::Mat prob3, var3;
    cv::cvtColor(prob, prob3, cv::COLOR_GRAY2BGR);
    cv::applyColorMap(var, var3, cv::COLORMAP_VIRIDIS);
    const int x0 = static_cast<int>(k) * (w + 4);
    prob3.copyTo(canvas(cv::Rect(x0, kTitle, w, h)));
    var3.copyTo(canvas(cv::Rect(x0, 2 * kTitle + h, w, h)));
    cv::putText(canvas, panels[k].title + ": p(occupied)", {x0 + 4, 17}, cv::FONT_HERSHEY_SIMPLEX,
                0.5, {0, 0, 0}, 1);
    cv::putText(canvas, "log10 var (1e-3..1e4)", {x0 + 4, h + kTitle + 17},
                cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1);
  }
  WriteImage(png_path, canvas);
}

}  // namespace foresight::occupancy
