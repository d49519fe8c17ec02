#pragma once
/// The ego frame of an observed track, shared by training (models/) and the engines (inference/)
/// so that features and predictions mean the same thing in both.
///
/// Origin: the last observed point. x axis: along the displacement from the first to the last
/// observed point (identity rotation when `rotate` is false or the displacement is below 1 mm).
/// A trajectory distribution predicted in the ego frame maps to the world exactly:
///   W_world = W_ego R',  V_world = R V_ego R',  U unchanged,  o_world(t) = origin + W_world'
///   phi(t).

#include <Eigen/Core>
#include <cmath>

namespace foresight {

struct EgoFrame {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  Eigen::Matrix2d rotation = Eigen::Matrix2d::Identity();  ///< columns: ego axes in world

  /// @param past [p x 2] or any row-indexable (x, y) sequence, oldest first, world frame (m).
  template <typename Getter>
  static EgoFrame FromPast(int p, Getter&& point, bool rotate) {
    EgoFrame f;
    const Eigen::Vector2d last = point(p - 1);
    f.origin = last;
    if (rotate) {
      const Eigen::Vector2d d = last - point(0);
      const double n = d.norm();
      if (n > 1e-3) {
        const double c = d.x() / n, s = d.y() / n;
        f.rotation << c, -s, s, c;
      }
    }
    return f;
  }
  Eigen::Vector2d ToEgo(const Eigen::Vector2d& p_world) const {
    return rotation.transpose() * (p_world - origin);
  }
  Eigen::Vector2d ToWorld(const Eigen::Vector2d& p_ego) const { return rotation * p_ego + origin; }
};

}  // namespace foresight
