#include "training/directional/plots.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.h"
#include "core/von_mises.h"
#include "training/image_io.h"

namespace foresight::directional {

Eigen::Matrix<double, Eigen::Dynamic, 2> GenerateTrajectory(const Map& map,
                                                            const Eigen::Vector2d& start, double t,
                                                            double step, int steps,
                                                            std::mt19937_64* rng) {
  auto ws = map.MakeWorkspace();
  Eigen::Matrix<double, Eigen::Dynamic, 2> path(steps + 1, 2);
  path.row(0) = start.transpose();
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Eigen::Vector2d p = start;
  const FeatureConfig& f = map.features().config();
  for (int n = 0; n < steps; ++n) {
    if (p.x() < f.x_min || p.x() > f.x_max || p.y() < f.y_min || p.y() > f.y_max) {
      path.conservativeResize(n + 1, 2);  // left the map
      break;
    }
    map.QueryOne(p.x(), p.y(), t, &ws);
    double u = u01(*rng), acc = 0;
    int r = 0;
    for (; r + 1 < map.components(); ++r) {
      acc += ws.alpha[r];
      if (u < acc) break;
    }
    const double theta = SampleVonMises(ws.mu[r], ws.kappa[r], rng);
    p += step * Eigen::Vector2d(std::cos(theta), std::sin(theta));
    path.row(n + 1) = p.transpose();
  }
  return path;
}

namespace {

struct Panel {
  std::string title;
  const Map* map;
  double t;
  double window;  ///< data within |t_i - t| <= window are drawn (infinite: all)
};

struct Canvas {
  Eigen::Vector4d e;  // x_min, x_max, y_min, y_max
  double scale;       // px per m
  int w, h;
  cv::Point Px(double x, double y, int x0, int y0) const {
    return {x0 + static_cast<int>(std::lround((x - e[0]) * scale)),
            y0 + static_cast<int>(std::lround((e[3] - y) * scale))};
  }
};

void Draw(const DirectionalSamples& data, const std::vector<Panel>& panels, const EvalConfig& eval,
          std::uint64_t seed, bool trajectories, const std::string& png) {
  const FeatureConfig& f = panels[0].map->features().config();
  Canvas cv_;
  cv_.e = Eigen::Vector4d(f.x_min, f.x_max, f.y_min, f.y_max);
  cv_.scale = 420.0 / std::max(f.x_max - f.x_min, f.y_max - f.y_min);
  cv_.w = static_cast<int>(std::ceil((f.x_max - f.x_min) * cv_.scale));
  cv_.h = static_cast<int>(std::ceil((f.y_max - f.y_min) * cv_.scale));
  constexpr int kTitle = 24, kPad = 8;
  cv::Mat canvas(cv_.h + kTitle + kPad, static_cast<int>(panels.size()) * (cv_.w + kPad), CV_8UC3,
                 cv::Scalar(255, 255, 255));
  const double cell = 0.5 * ((f.x_max - f.x_min) / f.cells_x + (f.y_max - f.y_min) / f.cells_y);
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const Panel& p = panels[k];
    const int x0 = static_cast<int>(k) * (cv_.w + kPad), y0 = kTitle;
    cv::rectangle(canvas, {x0, y0}, {x0 + cv_.w, y0 + cv_.h}, {180, 180, 180}, 1);
    for (Eigen::Index i = 0; i < data.size(); ++i) {
      if (std::abs(data.t[i] - p.t) > p.window) continue;
      // Data coloured by heading (hue), small dots.
      const double hue = (data.theta[i] + M_PI) / (2 * M_PI) * 179.0;
      cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(hue, 120, 230)), bgr;
      cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
      const cv::Vec3b c = bgr.at<cv::Vec3b>(0, 0);
      cv::circle(canvas, cv_.Px(data.x[i], data.y[i], x0, y0), 1, cv::Scalar(c[0], c[1], c[2]), -1);
    }
    auto ws = p.map->MakeWorkspace();
    cv::Mat roi = canvas(cv::Rect(x0, y0, cv_.w + 1, cv_.h + 1));  // drawing clipped to the panel
    if (!trajectories) {
      // Arrows on a grid of at most 24 x 24 points.
      const int nx = std::min(24, std::max(4, f.cells_x)),
                ny = std::min(24, std::max(4, f.cells_y));
      const double sx = (f.x_max - f.x_min) / nx, sy = (f.y_max - f.y_min) / ny;
      const double len = 0.45 * std::min(sx, sy);
      for (int iy = 0; iy < ny; ++iy)
        for (int ix = 0; ix < nx; ++ix) {
          const double x = f.x_min + (ix + 0.5) * sx, y = f.y_min + (iy + 0.5) * sy;
          p.map->QueryOne(x, y, p.t, &ws);
          for (int r = 0; r < p.map->components(); ++r) {
            if (ws.alpha[r] < 0.1) continue;
            const double l = len * std::sqrt(ws.alpha[r]);
            cv::arrowedLine(roi, cv_.Px(x, y, 0, 0),
                            cv_.Px(x + l * std::cos(ws.mu[r]), y + l * std::sin(ws.mu[r]), 0, 0),
                            {40, 40, 40}, 1, cv::LINE_AA, 0, 0.3);
          }
        }
    } else if (data.size() > 0) {
      std::mt19937_64 rng(seed + 7);
      std::uniform_int_distribution<Eigen::Index> pick(0, data.size() - 1);
      const double step = eval.plot_step > 0 ? eval.plot_step : cell / 6.0;
      for (int n = 0; n < eval.plot_trajectories; ++n) {
        Eigen::Index i = pick(rng);
        for (int tries = 0; tries < 50 && std::abs(data.t[i] - p.t) > p.window; ++tries)
          i = pick(rng);
        const auto path =
            GenerateTrajectory(*p.map, {data.x[i], data.y[i]}, p.t, step, eval.plot_steps, &rng);
        const cv::Scalar colour((37 * n) % 200, (91 * n + 60) % 200, 200);
        for (Eigen::Index s = 0; s + 1 < path.rows(); ++s)
          cv::line(roi, cv_.Px(path(s, 0), path(s, 1), 0, 0),
                   cv_.Px(path(s + 1, 0), path(s + 1, 1), 0, 0), colour, 2, cv::LINE_AA);
        cv::circle(roi, cv_.Px(path(0, 0), path(0, 1), 0, 0), 4, {0, 0, 220}, -1);
      }
    }
    cv::putText(canvas, p.title, {x0 + 4, 17}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1);
  }
  WriteImage(png, canvas);
}

}  // namespace

void PlotMaps(const DirectionalSamples& data, const Map& st, const Map* spatial,
              const EvalConfig& eval, std::uint64_t seed, const std::string& dir) {
  const FeatureConfig& f = st.features().config();
  const double range = f.t_max - f.t_min;
  auto fmt = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v);
    return std::string(b);
  };
  std::vector<Panel> panels;
  for (const double q : {0.25, 0.75}) {
    const double t = f.t_min + q * range;
    panels.push_back({std::string(VariantName(st.variant())) + ", t = " + fmt(t) + " s", &st, t,
                      range > 0 ? 0.25 * range : INFINITY});
  }
  if (spatial)
    panels.push_back({"spatial (all times)", spatial, 0.5 * (f.t_min + f.t_max), INFINITY});
  Draw(data, panels, eval, seed, false, dir + "/directions.png");
  Draw(data, panels, eval, seed, true, dir + "/trajectories.png");
}

}  // namespace foresight::directional
