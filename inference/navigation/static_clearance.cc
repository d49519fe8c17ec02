#include "inference/navigation/static_clearance.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace foresight::nav {

double SweptOccupancy(const occupancy::Map& map, occupancy::MapWorkspace* ws, double x, double y,
                      double radius, int num_angles) {
  double best = 0.0;
  for (int i = 0; i < num_angles; ++i) {
    const double phi = -M_PI + 2.0 * M_PI * i / num_angles;
    best =
        std::max(best, map.Probability(x + radius * std::sin(phi), y + radius * std::cos(phi), ws));
  }
  return best;
}

StaticCollisionField::StaticCollisionField(const occupancy::Map& map, double radius,
                                           double resolution, int num_angles)
    : map_(&map), radius_(radius), resolution_(resolution) {
  FS_THROW_UNLESS(radius > 0 && std::isfinite(radius), "static collision field: robot radius ",
                  radius, " must be > 0");
  FS_THROW_UNLESS(resolution > 0 && resolution <= radius, "static collision field: resolution ",
                  resolution, " must be in (0, robot radius ", radius, "]");
  num_angles_ = num_angles > 0
                    ? num_angles
                    : static_cast<int>(std::ceil(2.0 * M_PI * radius / (0.5 * resolution)));
  const Eigen::Vector4d e = map.Extent();
  FS_THROW_UNLESS(e.allFinite() && e[1] > e[0] && e[3] > e[2],
                  "static collision field: map extent [", e.transpose(), "] is empty");
  origin_ = {e[0] - radius, e[2] - radius};
  const int cols = static_cast<int>(std::ceil((e[1] - e[0] + 2 * radius) / resolution)) + 1;
  const int rows = static_cast<int>(std::ceil((e[3] - e[2] + 2 * radius) / resolution)) + 1;
  FS_THROW_UNLESS(static_cast<double>(rows) * cols < 5e7, "static collision field: ", rows, " x ",
                  cols, " cells at resolution ", resolution,
                  " m is too large; use a coarser resolution");
  raster_.resize(rows, cols);
  occupancy::MapWorkspace ws = map.MakeWorkspace();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      raster_(r, c) =
          static_cast<float>(SweptOccupancy(map, &ws, origin_.x() + c * resolution,
                                            origin_.y() + r * resolution, radius, num_angles_));
}

double StaticCollisionField::Value(double x, double y, occupancy::MapWorkspace* ws) const {
  if (map_ == nullptr) return 0.0;
  const double u = (x - origin_.x()) / resolution_, v = (y - origin_.y()) / resolution_;
  if (!(u >= 0 && v >= 0 && u < raster_.cols() - 1 && v < raster_.rows() - 1))
    return SweptOccupancy(*map_, ws, x, y, radius_, num_angles_);
  const int c = static_cast<int>(u), r = static_cast<int>(v);
  return std::max(std::max(raster_(r, c), raster_(r, c + 1)),
                  std::max(raster_(r + 1, c), raster_(r + 1, c + 1)));
}

}  // namespace foresight::nav
