#pragma once
/// OctoMap (Hornung et al. 2013, Debian liboctomap-dev) as an occupancy baseline on the same scans:
/// each scan's valid end points are inserted as a point cloud in the z = 0 plane from the laser
/// origin (ray casting, OctoMap's default sensor model); queries read the leaf's occupancy, 0.5
/// where unknown.

#include <cstdint>

#include "training/occupancy/pipeline.h"

namespace foresight::occupancy {

struct OctomapFigures {
  double insert_s = 0;  ///< wall-clock time to insert all training scans (median of repeats)
  double auc = 0, precision = 0, recall = 0;  ///< on data.test
  std::int64_t bytes = 0;   ///< writeBinary size (maximum-likelihood compressed tree)
  std::int64_t memory = 0;  ///< OcTree::memoryUsage()
};

OctomapFigures RunOctomapBaseline(const Data& data, double max_range, double resolution,
                                  int repeats);

}  // namespace foresight::occupancy
