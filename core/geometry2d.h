#pragma once
/// Small planar geometry shared by the simulators, generators and controllers.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace foresight {

/// Distance from x to the segment p-q (m), and the closest point (a point for p == q).
inline double DistanceToSegment(const Eigen::Vector2d& x, const Eigen::Vector2d& p,
                                const Eigen::Vector2d& q, Eigen::Vector2d* closest = nullptr) {
  const Eigen::Vector2d d = q - p;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0 ? std::clamp((x - p).dot(d) / l2, 0.0, 1.0) : 0.0;
  const Eigen::Vector2d c = p + t * d;
  if (closest) *closest = c;
  return (x - c).norm();
}

/// An angle wrapped to [-pi, pi] (rad).
inline double WrapToPi(double a) { return std::remainder(a, 2.0 * M_PI); }

}  // namespace foresight
