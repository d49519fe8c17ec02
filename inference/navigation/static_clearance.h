#pragma once
/// Static-obstacle collision check of SPAN (thesis ch 5, eq. staticCheck): the robot at x collides
/// when max_phi f_m(x + r [sin phi, cos phi]) > epsilon, the occupancy probability swept over the
/// circle of the robot's radius. The thesis evaluates the sweep by brute force at every step; here
/// the swept maximum is tabulated once per map on a fine raster (the map is static) and a query
/// takes the largest of the four raster values around x, so the inner loop of the optimiser costs
/// one lookup. Outside the raster the sweep is evaluated directly.

#include <Eigen/Core>
#include <vector>

#include "inference/mapping/occupancy_map.h"

namespace foresight::nav {

/// max over `num_angles` evenly spaced phi of f_m(x + r [sin phi, cos phi]) (eq. staticCheck).
double SweptOccupancy(const occupancy::Map& map, occupancy::MapWorkspace* ws, double x, double y,
                      double radius, int num_angles);

class StaticCollisionField {
 public:
  StaticCollisionField() = default;
  /// Tabulates the sweep over the map's extent grown by `radius` at `resolution` (m).
  /// @param num_angles sweep angles; 0 picks ceil(2 pi radius / (resolution / 2)).
  StaticCollisionField(const occupancy::Map& map, double radius, double resolution,
                       int num_angles = 0);

  bool empty() const { return map_ == nullptr; }
  /// Workspace for Value() (used for queries outside the raster).
  occupancy::MapWorkspace MakeWorkspace() const {
    return map_ ? map_->MakeWorkspace() : occupancy::MapWorkspace();
  }
  double radius() const { return radius_; }
  double resolution() const { return resolution_; }
  /// Swept occupancy near (x, y): max of the four surrounding raster values (the exact sweep
  /// outside the raster).
  double Value(double x, double y, occupancy::MapWorkspace* ws) const;
  /// Value(x, y) > epsilon.
  bool Collides(double x, double y, double epsilon, occupancy::MapWorkspace* ws) const {
    return Value(x, y, ws) > epsilon;
  }
  const Eigen::MatrixXf& raster() const {
    return raster_;
  }  ///< [rows (y) x cols (x)], row 0 at y_min
  Eigen::Vector2d origin() const { return origin_; }

 private:
  const occupancy::Map* map_ = nullptr;
  double radius_ = 0, resolution_ = 0.05;
  int num_angles_ = 0;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();  ///< position of raster(0, 0)
  Eigen::MatrixXf raster_;
};

}  // namespace foresight::nav
