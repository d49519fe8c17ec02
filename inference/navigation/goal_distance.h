#pragma once
/// Distance to the goal around static obstacles: the geodesic (shortest-path) distance from every
/// free cell of the swept-occupancy raster to the goal, by Dijkstra on the 8-connected grid
/// (over-estimates the Euclidean length of a free straight line by at most 8 %, exact along axes
/// and diagonals). SPAN uses it in place of ||x(T) - g|| (thesis eq. costOpt) so that a wall
/// between robot and goal does not trap the constant-control optimiser in front of it; where the
/// segment to the goal is free the two agree up to that grid error. Steps within `margin` of the
/// collision boundary cost up to (1 + margin_weight) times their length, so the descent keeps off
/// obstacle corners instead of grazing them (a path that must squeeze through still exists).

#include <Eigen/Core>
#include <vector>

#include "inference/navigation/static_clearance.h"

namespace foresight::nav {

class GoalDistanceField {
 public:
  GoalDistanceField() = default;
  /// Free cells: swept occupancy <= epsilon. A goal on an occupied cell starts from the nearest
  /// free one.
  GoalDistanceField(const StaticCollisionField& field, const Eigen::Vector2d& goal, double epsilon,
                    double margin = 0.5, double margin_weight = 3.0);

  const Eigen::Vector2d& goal() const { return goal_; }
  bool empty() const { return distance_.size() == 0; }
  /// Geodesic distance (m), bilinear between cells; outside the raster or on cells that cannot
  /// reach the goal: the Euclidean distance plus `unreachable_penalty`.
  double Distance(const Eigen::Vector2d& x) const;
  double unreachable_penalty = 50.0;
  double margin_weight() const { return margin_weight_; }
  /// True when x lies on a cell that reaches the goal.
  bool Reaches(const Eigen::Vector2d& x) const {
    return Distance(x) < (x - goal_).norm() + 0.5 * unreachable_penalty;
  }

 private:
  Eigen::Vector2d goal_ = Eigen::Vector2d::Zero(), origin_ = Eigen::Vector2d::Zero();
  double resolution_ = 0.05, margin_weight_ = 0;
  Eigen::MatrixXf distance_;  ///< [rows x cols] like the field's raster; +inf where unreachable
};

}  // namespace foresight::nav
