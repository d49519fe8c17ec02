#include "models/occupancy/grid_builder.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/error.h"

namespace foresight::occupancy {
namespace {
double Logit(double p) { return std::log(p / (1.0 - p)); }
}  // namespace

void TraverseCells(double x0, double y0, double x1, double y1,
                   std::vector<std::pair<int, int>>* cells) {
  cells->clear();
  int ix = static_cast<int>(std::floor(x0)), iy = static_cast<int>(std::floor(y0));
  const int ex = static_cast<int>(std::floor(x1)), ey = static_cast<int>(std::floor(y1));
  const double dx = x1 - x0, dy = y1 - y0;
  const int sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double tdx = dx != 0 ? std::abs(1.0 / dx) : kInf, tdy = dy != 0 ? std::abs(1.0 / dy) : kInf;
  double tx = dx != 0 ? ((sx > 0 ? (ix + 1 - x0) : (x0 - ix)) * tdx) : kInf;
  double ty = dy != 0 ? ((sy > 0 ? (iy + 1 - y0) : (y0 - iy)) * tdy) : kInf;
  cells->emplace_back(ix, iy);
  const int max_steps = std::abs(ex - ix) + std::abs(ey - iy);
  for (int step = 0; step < max_steps && (ix != ex || iy != ey); ++step) {
    if (tx < ty) {
      ix += sx;
      tx += tdx;
    } else {
      iy += sy;
      ty += tdy;
    }
    cells->emplace_back(ix, iy);
  }
  if (cells->back() != std::make_pair(ex, ey)) cells->emplace_back(ex, ey);
}

GridMap BuildGridMap(const GridMapConfig& c, const std::vector<LaserScan>& scans) {
  FS_THROW_UNLESS(c.x_max > c.x_min && c.y_max > c.y_min, "grid map: empty extent [", c.x_min, ", ",
                  c.x_max, "] x [", c.y_min, ", ", c.y_max, "]");
  GridGeometry g;
  g.x_min = c.x_min;
  g.y_min = c.y_min;
  g.resolution = c.resolution;
  const double fx = std::ceil((c.x_max - c.x_min) / c.resolution - 1e-9);
  const double fy = std::ceil((c.y_max - c.y_min) / c.resolution - 1e-9);
  FS_THROW_UNLESS(fx * fy <= double(1 << 28), "grid map: ", fx, " x ", fy, " cells is too many");
  g.nx = static_cast<int>(fx);
  g.ny = static_cast<int>(fy);
  const double l_hit = Logit(c.p_hit), l_miss = Logit(c.p_miss);
  const double l_min = Logit(c.p_min), l_max = Logit(c.p_max);
  std::vector<float> logodds(static_cast<std::size_t>(g.nx) * g.ny, 0.0f);
  std::vector<std::uint8_t> known(logodds.size(), 0);
  // Per-scan marks: 1 free, 2 occupied; stamped with the scan number to avoid clearing.
  std::vector<std::int32_t> stamp(logodds.size(), -1);
  std::vector<std::uint8_t> mark(logodds.size(), 0);
  std::vector<std::size_t> touched;
  std::vector<std::pair<int, int>> ray;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    const LaserScan& scan = scans[s];
    if (!std::isfinite(scan.x) || !std::isfinite(scan.y) || !std::isfinite(scan.theta)) continue;
    touched.clear();
    const double ox = (scan.x - g.x_min) / g.resolution, oy = (scan.y - g.y_min) / g.resolution;
    for (int b = 0; b < scan.num_beams(); ++b) {
      const double r = scan.ranges[b];
      if (!(r > 0 && r < c.max_range)) continue;
      const double a = scan.BeamAngle(b);
      const double px = ox + r * std::cos(a) / g.resolution,
                   py = oy + r * std::sin(a) / g.resolution;
      TraverseCells(ox, oy, px, py, &ray);
      for (std::size_t i = 0; i < ray.size(); ++i) {
        const auto [ix, iy] = ray[i];
        if (ix < 0 || iy < 0 || ix >= g.nx || iy >= g.ny) continue;
        const std::size_t cell = static_cast<std::size_t>(iy) * g.nx + ix;
        const std::uint8_t m = i + 1 == ray.size() ? 2 : 1;
        if (stamp[cell] != static_cast<std::int32_t>(s)) {
          stamp[cell] = static_cast<std::int32_t>(s);
          mark[cell] = m;
          touched.push_back(cell);
        } else if (m > mark[cell]) {
          mark[cell] = m;
        }
      }
    }
    for (const std::size_t cell : touched) {
      const double l = logodds[cell] + (mark[cell] == 2 ? l_hit : l_miss);
      logodds[cell] = static_cast<float>(std::clamp(l, l_min, l_max));
      known[cell] = 1;
    }
  }
  Eigen::MatrixXf p(g.ny, g.nx);
  for (int iy = 0; iy < g.ny; ++iy) {
    for (int ix = 0; ix < g.nx; ++ix) {
      const std::size_t cell = static_cast<std::size_t>(iy) * g.nx + ix;
      p(iy, ix) = known[cell] ? static_cast<float>(1.0 / (1.0 + std::exp(-logodds[cell])))
                              : std::numeric_limits<float>::quiet_NaN();
    }
  }
  return GridMap(g, std::move(p), c.cell_type);
}

}  // namespace foresight::occupancy
