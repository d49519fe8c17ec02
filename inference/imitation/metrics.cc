#include "inference/imitation/metrics.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace foresight::imitation {

double ArcLength(const Eigen::MatrixXd& path) {
  double length = 0;
  for (Eigen::Index j = 1; j < path.cols(); ++j) length += (path.col(j) - path.col(j - 1)).norm();
  return length;
}

Eigen::MatrixXd ResampleByArcLength(const Eigen::MatrixXd& path, int count) {
  FS_THROW_UNLESS(count >= 2, "ResampleByArcLength: count must be >= 2, got ", count);
  FS_THROW_UNLESS(path.cols() >= 1 && path.rows() >= 1, "ResampleByArcLength: empty path [",
                  path.rows(), " x ", path.cols(), "]");
  FS_THROW_UNLESS(path.allFinite(), "ResampleByArcLength: path has non-finite points");
  const Eigen::Index n = path.cols();
  Eigen::VectorXd cumulative(n);
  cumulative(0) = 0;
  for (Eigen::Index j = 1; j < n; ++j)
    cumulative(j) = cumulative(j - 1) + (path.col(j) - path.col(j - 1)).norm();
  const double length = cumulative(n - 1);
  Eigen::MatrixXd out(path.rows(), count);
  if (length <= 0) {
    out.colwise() = path.col(0);
    return out;
  }
  Eigen::Index seg = 1;  // current segment [seg - 1, seg]
  for (int k = 0; k < count; ++k) {
    const double target = length * k / (count - 1);
    while (seg < n - 1 && cumulative(seg) < target) ++seg;
    const double span = cumulative(seg) - cumulative(seg - 1);
    const double u = span > 0 ? std::clamp((target - cumulative(seg - 1)) / span, 0.0, 1.0) : 1.0;
    out.col(k) = path.col(seg - 1) + u * (path.col(seg) - path.col(seg - 1));
  }
  out.col(0) = path.col(0);
  out.col(count - 1) = path.col(n - 1);
  return out;
}

double DiscreteFrechet(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  FS_THROW_UNLESS(a.rows() == b.rows(), "DiscreteFrechet: paths of dimension ", a.rows(), " and ",
                  b.rows());
  FS_THROW_UNLESS(a.cols() >= 1 && b.cols() >= 1, "DiscreteFrechet: a path has no points (",
                  a.cols(), " and ", b.cols(), ")");
  const Eigen::Index n = a.cols(), m = b.cols();
  // row(j) holds c(i, j) for the current i; `diagonal` keeps c(i-1, j-1) before it is overwritten.
  Eigen::VectorXd row(m);
  row(0) = (a.col(0) - b.col(0)).norm();
  for (Eigen::Index j = 1; j < m; ++j) row(j) = std::max(row(j - 1), (a.col(0) - b.col(j)).norm());
  for (Eigen::Index i = 1; i < n; ++i) {
    double diagonal = row(0);
    row(0) = std::max(row(0), (a.col(i) - b.col(0)).norm());
    for (Eigen::Index j = 1; j < m; ++j) {
      const double reach = std::min({row(j), diagonal, row(j - 1)});
      diagonal = row(j);
      row(j) = std::max(reach, (a.col(i) - b.col(j)).norm());
    }
  }
  return row(m - 1);
}

Eigen::VectorXd DistanceToNearest(const Eigen::MatrixXd& path,
                                  const std::vector<Eigen::MatrixXd>& references) {
  Eigen::Index points = 0;
  for (std::size_t k = 0; k < references.size(); ++k) {
    FS_THROW_UNLESS(references[k].rows() == path.rows(), "DistanceToNearest: reference ", k,
                    " has dimension ", references[k].rows(), ", the path ", path.rows());
    points += references[k].cols();
  }
  FS_THROW_UNLESS(points > 0, "DistanceToNearest: no reference points");
  Eigen::VectorXd out(path.cols());
  for (Eigen::Index j = 0; j < path.cols(); ++j) {
    double best = INFINITY;
    for (const Eigen::MatrixXd& ref : references)
      if (ref.cols() > 0)
        best = std::min(best, (ref.colwise() - path.col(j)).colwise().norm().minCoeff());
    out(j) = best;
  }
  return out;
}

double SphereObstacle::SignedDistance(const Eigen::VectorXd& p) const {
  FS_THROW_UNLESS(p.size() == centre.size(), "SphereObstacle::SignedDistance: point of dimension ",
                  p.size(), ", centre of dimension ", centre.size());
  return (p - centre).norm() - radius;
}

double CylinderObstacle::SignedDistance(const Eigen::Vector3d& p) const {
  const double e_r = (p.head<2>() - axis_xy).norm() - radius;
  const double e_z = std::abs(p.z() - 0.5 * (z_min + z_max)) - 0.5 * (z_max - z_min);
  return std::min(std::max(e_r, e_z), 0.0) + std::hypot(std::max(e_r, 0.0), std::max(e_z, 0.0));
}

namespace {

void CheckPath(const Eigen::MatrixXd& path, double body_radius, const char* obstacle) {
  FS_THROW_UNLESS(path.cols() >= 1, "MaxCollisionDepth (", obstacle, "): path has no points");
  FS_THROW_UNLESS(path.allFinite(), "MaxCollisionDepth (", obstacle,
                  "): path has non-finite points");
  FS_THROW_UNLESS(std::isfinite(body_radius) && body_radius >= 0, "MaxCollisionDepth (", obstacle,
                  "): body_radius must be finite and >= 0, got ", body_radius);
}

}  // namespace

double MaxCollisionDepth(const Eigen::MatrixXd& path, const SphereObstacle& obstacle,
                         double body_radius) {
  CheckPath(path, body_radius, "sphere");
  FS_THROW_UNLESS(path.rows() == obstacle.centre.size(), "MaxCollisionDepth (sphere): path of ",
                  "dimension ", path.rows(), ", obstacle centre of dimension ",
                  obstacle.centre.size());
  FS_THROW_UNLESS(obstacle.radius >= 0, "MaxCollisionDepth (sphere): radius ", obstacle.radius,
                  " < 0");
  double depth = 0;
  for (Eigen::Index j = 0; j < path.cols(); ++j)
    depth =
        std::max(depth, body_radius - ((path.col(j) - obstacle.centre).norm() - obstacle.radius));
  return depth;
}

double MaxCollisionDepth(const Eigen::MatrixXd& path, const CylinderObstacle& obstacle,
                         double body_radius) {
  CheckPath(path, body_radius, "cylinder");
  FS_THROW_UNLESS(path.rows() == 3, "MaxCollisionDepth (cylinder): path of dimension ", path.rows(),
                  ", expected 3");
  FS_THROW_UNLESS(obstacle.radius >= 0 && obstacle.z_max >= obstacle.z_min,
                  "MaxCollisionDepth (cylinder): invalid cylinder (radius ", obstacle.radius,
                  ", z from ", obstacle.z_min, " to ", obstacle.z_max, ")");
  double depth = 0;
  for (Eigen::Index j = 0; j < path.cols(); ++j)
    depth = std::max(depth, body_radius - obstacle.SignedDistance(path.col(j)));
  return depth;
}

bool ReachedGoal(const Eigen::MatrixXd& path, const Eigen::VectorXd& goal, double tolerance) {
  FS_THROW_UNLESS(path.cols() >= 1, "ReachedGoal: path has no points");
  FS_THROW_UNLESS(path.rows() == goal.size(), "ReachedGoal: path of dimension ", path.rows(),
                  ", goal of dimension ", goal.size());
  FS_THROW_UNLESS(tolerance >= 0, "ReachedGoal: tolerance must be >= 0, got ", tolerance);
  const double distance = (path.col(path.cols() - 1) - goal).norm();
  return std::isfinite(distance) && distance <= tolerance;
}

}  // namespace foresight::imitation
