#pragma once
/// A planar laser scan: the common in-memory form of every occupancy dataset (CARMEN logs, the
/// synthetic floor plan). Labelled occupancy points are made from scans by
/// datasets/occupancy_points.h.

#include <vector>

namespace foresight {

/// One planar laser scan in the world frame W.
struct LaserScan {
  double time = 0;                 ///< s
  int robot = 0;                   ///< recording robot (0 for single-robot logs)
  double x = 0, y = 0, theta = 0;  ///< laser pose X_WL: position (m) and heading (rad)
  double angle_min = 0;            ///< angle of beam 0 relative to theta (rad)
  double angle_increment = 0;      ///< angle between consecutive beams (rad)
  std::vector<double> ranges;      ///< m; readings >= max range or non-finite are "no return"
  /// World angle of beam `i` (rad): theta + angle_min + i * angle_increment.
  double BeamAngle(int i) const { return theta + angle_min + i * angle_increment; }
  int num_beams() const { return static_cast<int>(ranges.size()); }
};

}  // namespace foresight
