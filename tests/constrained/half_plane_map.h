#pragma once
// A smooth half-plane occupancy map for the constrained-prediction tests.

#include <cmath>
#include <string>

#include "inference/mapping/occupancy_map.h"

namespace foresight::constrained {

// p = sigmoid(k (a'x - b)) with its exact gradient k p (1 - p) a.
class SmoothHalfPlane final : public occupancy::Map {
 public:
  SmoothHalfPlane(Eigen::Vector2d a, double b, double k) : a_(a), b_(b), k_(k) {}
  std::string model_type() const override { return "test.smooth_half_plane"; }
  occupancy::MapWorkspace MakeWorkspace() const override { return {}; }
  occupancy::QueryResult Query(double x, double y, occupancy::MapWorkspace*) const override {
    occupancy::QueryResult q;
    q.probability = 1 / (1 + std::exp(-k_ * (a_.x() * x + a_.y() * y - b_)));
    const double d = k_ * q.probability * (1 - q.probability);
    q.dp_dx = d * a_.x();
    q.dp_dy = d * a_.y();
    return q;
  }
  Eigen::Vector4d Extent() const override { return {-1e3, 1e3, -1e3, 1e3}; }

 private:
  Eigen::Vector2d a_;
  double b_, k_;
};

}  // namespace foresight::constrained
