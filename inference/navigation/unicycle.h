#pragma once
/// The robot of SPAN (thesis ch 5, eq. EqnMotion): a unicycle with state (x, y, heading) and
/// controls (v, omega), integrated with explicit Euler steps ("single shooting", dt = 0.1 s).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace foresight::nav {

struct UnicycleState {
  double x = 0, y = 0;  ///< position (m, world frame)
  double heading = 0;   ///< rad, counter-clockwise from +x
  Eigen::Vector2d position() const { return {x, y}; }
};

struct Control {
  double v = 0;      ///< linear velocity (m/s)
  double omega = 0;  ///< angular velocity (rad/s)
};

/// Control limits: v in [v_min, v_max], omega in [-omega_max, omega_max].
struct ControlLimits {
  double v_min = -1.0, v_max = 1.0, omega_max = 1.0;
  Control Clamp(const Control& u) const {
    return {std::clamp(u.v, v_min, v_max), std::clamp(u.omega, -omega_max, omega_max)};
  }
};

/// One Euler step: x += v cos(h) dt, y += v sin(h) dt, h += omega dt.
inline UnicycleState EulerStep(const UnicycleState& s, const Control& u, double dt) {
  return {s.x + u.v * std::cos(s.heading) * dt, s.y + u.v * std::sin(s.heading) * dt,
          s.heading + u.omega * dt};
}

}  // namespace foresight::nav
