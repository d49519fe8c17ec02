#pragma once
/// Joint-space types shared by the manipulation runtime: the robot model, worlds (start and goal
/// configurations), validity, fabrics, GFCS and the planners. The Panda has seven arm joints.

#include <Eigen/Core>

namespace foresight::manipulation {

/// Number of actuated arm joints (Franka Emika Panda).
inline constexpr int kDof = 7;

/// [kDof] joint angles (rad), velocities (rad/s) or accelerations (rad/s^2).
using JointVector = Eigen::Matrix<double, kDof, 1>;

/// [3 x kDof] Jacobian of a point's world position with respect to the joint angles (m/rad).
using PointJacobian = Eigen::Matrix<double, 3, kDof>;

}  // namespace foresight::manipulation
