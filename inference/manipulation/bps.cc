#include "inference/manipulation/bps.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace foresight::manipulation {
namespace {

constexpr double kSlack = 1e-9;
constexpr const char* kAxis[3] = {"x", "y", "z"};

}  // namespace

void BpsLattice::Validate(const std::string& where) const {
  FS_THROW_UNLESS(std::isfinite(spacing) && spacing > 0, where, ": bps lattice spacing ", spacing,
                  " must be finite and positive");
  FS_THROW_UNLESS(std::isfinite(max_distance) && max_distance > 0, where,
                  ": bps lattice max_distance ", max_distance, " must be finite and positive");
  for (int a = 0; a < 3; ++a) {
    FS_THROW_UNLESS(std::isfinite(lower[a]) && std::isfinite(upper[a]), where,
                    ": bps lattice bounds on ", kAxis[a], " must be finite (lower ", lower[a],
                    ", upper ", upper[a], ")");
    FS_THROW_UNLESS(lower[a] <= upper[a], where, ": bps lattice lower.", kAxis[a], " = ", lower[a],
                    " is above upper.", kAxis[a], " = ", upper[a]);
  }
  const Eigen::Vector3d n = ((upper - lower) / spacing).array().floor() + 1.0;
  FS_THROW_UNLESS(n.prod() <= 1e6, where, ": bps lattice has ", n.prod(), " points (spacing ",
                  spacing, "), more than 10^6");
}

Eigen::Vector3i BpsLattice::counts() const {
  Eigen::Vector3i n;
  for (int a = 0; a < 3; ++a)
    n[a] = static_cast<int>(std::floor((upper[a] - lower[a] + kSlack) / spacing)) + 1;
  return n;
}

int BpsLattice::size() const { return counts().prod(); }

Eigen::Matrix3Xd BpsLattice::points() const {
  const Eigen::Vector3i n = counts();
  Eigen::Matrix3Xd p(3, n.prod());
  int c = 0;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) p.col(c++) = lower + spacing * Eigen::Vector3d(i, j, k);
  return p;
}

Eigen::VectorXf EncodeBps(const World& world, const BpsLattice& lattice) {
  lattice.Validate("EncodeBps");
  const Eigen::Matrix3Xd p = lattice.points();
  Eigen::VectorXf d(p.cols());
  for (Eigen::Index r = 0; r < p.cols(); ++r) {
    double best = lattice.max_distance;
    for (int i = 0; i < world.num_obstacles(); ++i)
      best = std::min(best, std::abs(world.ObstacleSignedDistance(i, p.col(r), nullptr)));
    d[r] = static_cast<float>(best);
  }
  return d;
}

void CheckLatticeCovers(const BpsLattice& lattice, const Eigen::AlignedBox3d& workspace,
                        const std::string& where) {
  lattice.Validate(where);
  FS_THROW_UNLESS(!workspace.isEmpty(), where, ": the workspace box to cover is empty");
  const Eigen::Vector3d last =
      lattice.lower + lattice.spacing * (lattice.counts().array() - 1).cast<double>().matrix();
  for (int a = 0; a < 3; ++a) {
    FS_THROW_UNLESS(lattice.lower[a] <= workspace.min()[a] + kSlack, where,
                    ": the bps lattice does not cover the workspace on ", kAxis[a],
                    ": its first point ", lattice.lower[a], " is above the workspace minimum ",
                    workspace.min()[a], " (m)");
    FS_THROW_UNLESS(last[a] >= workspace.max()[a] - kSlack, where,
                    ": the bps lattice does not cover the workspace on ", kAxis[a],
                    ": its last point ", last[a], " (upper ", lattice.upper[a],
                    ") is below the workspace maximum ", workspace.max()[a], " (m)");
  }
}

Eigen::AlignedBox3d ReachBox(const RobotModel& robot) {
  FS_THROW_UNLESS(robot.num_spheres() > 0 && robot.joint_names().size() == kDof,
                  "ReachBox: the robot model has no arm joints or no collision spheres");
  KinematicsData data = robot.MakeData();
  ForwardKinematics(robot, JointVector::Zero(), &data);
  // chain[b] = |o_2 - o_1| + ... + |o_b - o_{b-1}| (body b >= 1 turns about joint b, origin o_b).
  double chain[kDof + 1] = {0};
  for (int b = 2; b <= kDof; ++b)
    chain[b] = chain[b - 1] + (data.p_WJ[b - 1] - data.p_WJ[b - 2]).norm();
  const Eigen::Vector3d o1 = data.p_WJ[0];
  Eigen::AlignedBox3d box;
  double reach = 0;
  for (int s = 0; s < robot.num_spheres(); ++s) {
    const CollisionSphere& sphere = robot.spheres()[s];
    const int body = robot.num_supporting_joints(sphere.link);
    const Eigen::Vector3d c = data.p_WS.col(s);
    if (body == 0) {
      box.extend(c - Eigen::Vector3d::Constant(sphere.radius));
      box.extend(c + Eigen::Vector3d::Constant(sphere.radius));
    } else {
      reach = std::max(reach, chain[body] + (c - data.p_WJ[body - 1]).norm() + sphere.radius);
    }
  }
  box.extend(o1 - Eigen::Vector3d::Constant(reach));
  box.extend(o1 + Eigen::Vector3d::Constant(reach));
  return box;
}

}  // namespace foresight::manipulation
