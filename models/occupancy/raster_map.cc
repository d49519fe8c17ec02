#include "models/occupancy/raster_map.h"

#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/hinge_grid.h"
#include "inference/mapping/grid_map.h"
#include "models/occupancy/fast_bhm.h"

namespace foresight::occupancy {

void WriteRasterMap(const OccupancyRaster& raster, const RasterMapOptions& o,
                    const std::string& path, const std::string& config_yaml, std::int64_t seed) {
  FS_THROW_UNLESS(o.sample_step > 0 && o.spacing > 0 && o.margin >= 0, "raster map: sample_step (",
                  o.sample_step, ") and spacing (", o.spacing, ") must be positive and margin (",
                  o.margin, ") non-negative");
  FS_THROW_UNLESS(raster.cells.size() > 0, "raster map: the obstacle raster is empty");
  const Eigen::Vector4d e = raster.extent;
  const double step = o.sample_step, margin = o.margin;
  const int nx = static_cast<int>(std::ceil((e[1] - e[0] + 2 * margin) / step));
  const int ny = static_cast<int>(std::ceil((e[3] - e[2] + 2 * margin) / step));
  if (o.kind == RasterMapKind::kGrid) {
    GridGeometry g;
    g.x_min = e[0] - margin;
    g.y_min = e[2] - margin;
    g.resolution = step;
    g.nx = nx;
    g.ny = ny;
    Eigen::MatrixXf p(ny, nx);
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = 0; ix < nx; ++ix) {
        int occ = 0;
        for (int sy = 0; sy < 4; ++sy)
          for (int sx = 0; sx < 4; ++sx)
            occ += raster.Occupied(g.x_min + (ix + (sx + 0.5) / 4) * step,
                                   g.y_min + (iy + (sy + 0.5) / 4) * step);
        p(iy, ix) = 0.05f + 0.9f * static_cast<float>(occ) / 16.0f;
      }
    GridMap(g, p, CellType::kFloat32).Save(path, config_yaml, seed);
    return;
  }
  HingeGridConfig hg;
  hg.x_min = e[0] - margin;
  hg.x_max = e[1] + margin;
  hg.y_min = e[2] - margin;
  hg.y_max = e[3] + margin;
  hg.spacing = o.spacing;
  hg.gamma = 6.71 * std::pow(0.5 / o.spacing, 2);  // the thesis' 0.5 m / 6.71 pairing, rescaled
  hg.cutoff_radius = 2.0 * o.spacing;
  FastBhmLearner learner{HingeGrid(hg), FastBhmConfig{}};
  // Labelled points on the raster's sampling grid, fed in row strips like scans.
  Eigen::Matrix2Xd xy(2, nx);
  std::vector<std::uint8_t> label(static_cast<std::size_t>(nx));
  for (int iy = 0; iy < ny; ++iy) {
    const double y = hg.y_min + (iy + 0.5) * step;
    for (int ix = 0; ix < nx; ++ix) {
      const double x = hg.x_min + (ix + 0.5) * step;
      xy.col(ix) = Eigen::Vector2d(x, y);
      label[static_cast<std::size_t>(ix)] = raster.Occupied(x, y) ? 1 : 0;
    }
    learner.Update(xy, label.data());
  }
  learner.ToMap().Save(path, config_yaml, seed);
}

}  // namespace foresight::occupancy
