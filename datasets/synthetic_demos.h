#pragma once
/// Synthetic demonstrations with known ground truth, for tests and the imitation experiments:
///
/// - SyntheticDemos2d: 2-D handwriting-like demos. A shape family has a base curve b(s), s in [0,
/// 1],
///   shifted so that b(1) = (0, 0) is the goal. Demo i follows
///     x_i(s) = b(s) + (1 - s)^2 (c_i0 + c_i1 sin(pi s) + c_i2 sin(2 pi s)),  c_ik ~ N(0, noise^2
///     I),
///   a smooth perturbation that vanishes (with its slope) at the goal, so every demo ends exactly
///   at (0, 0). Time: s = sigma(t / T_i) with sigma(u) = 1 - (1 - u)^3 (moving at the start, at
///   rest at the goal), T_i = 5 (1 + noise u_i) s, u_i ~ U[-1, 1]; `points` samples equally spaced
///   in time; velocities analytic: x_dot = x'(s) sigma'(t / T_i) / T_i. Families (none
///   self-intersects):
///     "s_curve"  b(s) = (0.5 cos(3 pi s), 1 - s) - b(1)             (three half swings, like LASA
///     Sshape) "arc"      b(s) = (cos th, sin th) - b(1), th = 1.25 pi (1 - s)  (a 225-degree arc
///     of a unit circle) "zigzag"   b(s) = (s - 1, 0.3 (2 / pi) asin(0.95 sin(3 pi s)))    (a
///     zigzag with rounded corners)
///
/// - TaskSpaceDemos: end-effector positions (m) of a 6-DoF JACO arm (base at the origin, z up), the
///   documented substitute for the thesis's unpublished JACO recordings (ch 8, "pushing a box (7
///   demonstrations)", "lifting a box, by reaching inside and abruptly moving upwards (8
///   demonstrations)"). Each demo is a clamped cubic spline (zero velocity at both ends, C2)
///   through waypoints with knot times proportional to chord length, duration T_i in [4.5, 5.5] s,
///   kPointsPerTaskDemo samples equally spaced in time, velocities analytic (spline derivative).
///   Per demo the start and the intermediate waypoints are moved by independent uniform offsets of
///   a few cm (less for those at table height or inside the box); the goal is exact and common.
///     "push_box": start above and behind the box, descend to table height (z = 0.12 m), then push
///                 horizontally to the goal (0.58, -0.10, 0.12).
///     "lift_box": reach forward and down into a box (z = 0.12 m), then move abruptly upward to the
///                 goal (0.52, 0.10, 0.50).
///   Every point stays within 0.3-0.75 m horizontal distance from the base axis and 0.08-0.6 m
///   height.
///
/// Both are deterministic per seed (own draws on mt19937_64, the same with every standard library).

#include <cstdint>
#include <string>
#include <vector>

#include "datasets/demonstrations.h"

namespace foresight {

struct SyntheticDemoConfig {
  int demos = 7;        ///< >= 1
  int points = 200;     ///< samples per demo, >= 3
  double noise = 0.05;  ///< std of the perturbation coefficients (units of the shape, ~1)
  std::uint64_t seed = 1;
  std::string shape = "s_curve";  ///< one of SyntheticShapes()
};

/// "arc", "s_curve", "zigzag".
std::vector<std::string> SyntheticShapes();

/// A 2-D DemoSet named after the shape. Error on an unknown shape (naming the known ones),
/// demos < 1, points < 3, or a negative or non-finite noise.
DemoSet SyntheticDemos2d(const SyntheticDemoConfig& config);

/// "lift_box", "push_box".
std::vector<std::string> TaskSpaceTasks();
constexpr int kPushBoxDemos = 7;  ///< the thesis's number of recorded demonstrations
constexpr int kLiftBoxDemos = 8;
constexpr int kPointsPerTaskDemo = 200;

/// A 3-D DemoSet named after the task. Error on an unknown task (naming the known ones) or
/// demos < 1.
DemoSet TaskSpaceDemos(const std::string& task, int demos, std::uint64_t seed);

}  // namespace foresight
