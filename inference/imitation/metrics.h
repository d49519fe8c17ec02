#pragma once
/// Metrics of generated motions against demonstrations and obstacles (thesis ch 8, "Evaluation
/// Results", Table "Performance, as measured by Frechet Distance (F.D.) and Maximum Collision
/// Distance (M.C.D.)"). Paths are [d x n] matrices, one point per column. Both metrics are
/// evaluated "at fixed intervals along arc-length normalised generated trajectories": resample with
/// ResampleByArcLength first.
///
/// - Discrete Frechet distance (Eiter & Mannila 1994): with d(i, j) = ||a_i - b_j||,
///     c(0, 0) = d(0, 0),  c(i, j) = max(d(i, j), min(c(i-1, j), c(i-1, j-1), c(i, j-1)))
///   (terms with a negative index left out); F(a, b) = c(n-1, m-1). O(n m) time, O(m) memory.
/// - Trajectory distance: for each point of a path, the distance to the nearest point of any
///   reference (demonstration) path.
/// - Maximum collision depth of a path whose points are balls of radius r against an obstacle with
///   exact signed distance sd (negative inside): MCD = max_j max(0, r - sd(p_j)).

#include <Eigen/Core>
#include <vector>

namespace foresight::imitation {

/// [d x n] -> [d x count] points equally spaced in arc length along the polyline (linear
/// interpolation), the first and last points kept exactly; a path of zero length gives count copies
/// of its first point. Error for count < 2, n < 1, or non-finite points.
Eigen::MatrixXd ResampleByArcLength(const Eigen::MatrixXd& path, int count);

/// Total polyline length sum_j ||p_j+1 - p_j|| of a [d x n] path.
double ArcLength(const Eigen::MatrixXd& path);

/// Discrete Frechet distance between [d x n] and [d x m] paths (Euclidean). Error when the row
/// counts differ or a path has no points.
double DiscreteFrechet(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b);

/// [n]: for each point of `path` [d x n], the distance to the nearest point of any of the
/// `references` ([d x m_k] each; brute force). Error when a reference's dimension differs or there
/// are no reference points.
Eigen::VectorXd DistanceToNearest(const Eigen::MatrixXd& path,
                                  const std::vector<Eigen::MatrixXd>& references);

/// A ball ||p - centre|| <= radius in any dimension (a disc in 2-D).
struct SphereObstacle {
  Eigen::VectorXd centre;
  double radius = 0;
  /// ||p - centre|| - radius. Error when p's size differs from centre's.
  double SignedDistance(const Eigen::VectorXd& p) const;
};

/// A vertical capped cylinder: ||p_xy - axis_xy|| <= radius, z_min <= p_z <= z_max.
struct CylinderObstacle {
  Eigen::Vector2d axis_xy = Eigen::Vector2d::Zero();
  double z_min = 0, z_max = 0, radius = 0;
  /// Exact Euclidean signed distance: with e_r = ||p_xy - axis_xy|| - radius and
  /// e_z = |p_z - (z_min + z_max) / 2| - (z_max - z_min) / 2,
  ///   sd = min(max(e_r, e_z), 0) + ||(max(e_r, 0), max(e_z, 0))||.
  double SignedDistance(const Eigen::Vector3d& p) const;
};

/// max over points of max(0, body_radius - SignedDistance(p_j)) for a [d x n] path (n >= 1) of
/// balls of radius body_radius >= 0 (0: points). Error on a dimension mismatch (the cylinder needs
/// d = 3), a negative body_radius, or an invalid obstacle (radius < 0, z_max < z_min).
double MaxCollisionDepth(const Eigen::MatrixXd& path, const SphereObstacle& obstacle,
                         double body_radius);
double MaxCollisionDepth(const Eigen::MatrixXd& path, const CylinderObstacle& obstacle,
                         double body_radius);

/// Whether the last point of `path` [d x n] is within `tolerance` of `goal` [d] (false when it is
/// not finite). Error on a dimension mismatch, an empty path or a negative tolerance.
bool ReachedGoal(const Eigen::MatrixXd& path, const Eigen::VectorXd& goal, double tolerance);

}  // namespace foresight::imitation
