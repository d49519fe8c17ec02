#pragma once
/// An occupancy-map artifact fitted to an obstacle raster (a scenario's walls, a THOR or ETH
/// obstacle image): the map the navigation runtime and constrained prediction query for p(m = 1 |
/// x) and its gradient. Torch-free.

#include <cstdint>
#include <string>

#include "datasets/crowd_scenario.h"

namespace foresight::occupancy {

enum class RasterMapKind { kFastBhm, kGrid };

struct RasterMapOptions {
  RasterMapKind kind = RasterMapKind::kFastBhm;
  double sample_step = 0.1;  ///< labelled points (kFastBhm) / grid cells (kGrid) every this many m
  double spacing = 0.25;     ///< Fast-BHM inducing-point spacing (m); gamma scales as spacing^-2
  double margin = 1.0;       ///< the map covers the raster's extent grown by this much (m)
};

/// Fits the map and writes it to `path` (an occupancy.fast_bhm or occupancy.grid artifact;
/// `config_yaml` and `seed` are stored in it).
/// - kFastBhm: labelled points on the raster's sampling grid (outside the raster is occupied), fed
/// in
///   row strips like scans; hinge features with the thesis' 0.5 m / gamma 6.71 pairing rescaled to
///   `spacing`, cut off at 2 spacings.
/// - kGrid: the fraction of occupied raster samples in each cell (4 x 4 sub-samples) mapped to
///   [0.05, 0.95].
/// Non-positive steps or an empty raster are Errors naming the option.
void WriteRasterMap(const OccupancyRaster& raster, const RasterMapOptions& options,
                    const std::string& path, const std::string& config_yaml, std::int64_t seed);

}  // namespace foresight::occupancy
