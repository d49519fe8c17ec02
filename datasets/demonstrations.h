#pragma once
/// Demonstrations for imitation learning (thesis ch 8, "Imitating demonstrations"): N
/// demonstrations Xi = {{x_i1, ..., x_il_i}}_i, each a time-stamped sequence of states with
/// velocities, all ending at one goal (the equilibrium of the learned stable system). Shared by the
/// LASA reader (datasets/lasa.h), the synthetic generators (datasets/synthetic_demos.h), the
/// learners and the evaluation.
///
/// Columns are samples: a demonstration of n states in R^d is a [d x n] position matrix, a [d x n]
/// velocity matrix (units of position per second) and [n] strictly increasing time stamps (s).
/// A set without velocities keeps `velocity` empty (0 x 0) until FiniteDifferenceVelocities fills
/// it; CheckDemonstrations refuses such a set.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace foresight {

struct Demonstration {
  Eigen::MatrixXd position;  ///< [d x n] states
  Eigen::MatrixXd velocity;  ///< [d x n] d position / dt, or empty when not available
  Eigen::VectorXd time;      ///< [n] time stamps (s), strictly increasing
  int points() const { return static_cast<int>(position.cols()); }
};

struct DemoSet {
  std::string name;  ///< shown in every error message ("Sshape", "push_box", ...)
  int dimension = 0;
  std::vector<Demonstration> demos;
};

/// How far apart the demonstrations' final points are.
struct GoalSpread {
  Eigen::VectorXd goal;     ///< [d] mean of the final points
  double max_distance = 0;  ///< max_i ||x_i,last - goal||
  double extent = 0;        ///< max over axes of (max - min) over all positions of all demos
};

/// Validates a set and returns its goal spread. Refuses (Error naming the set, the demo index and
/// what): no demos, dimension < 1, a demo with fewer than 3 points, position/velocity/time sizes
/// that differ from [dimension x n]/[dimension x n]/[n], missing velocities, non-finite values,
/// time that does not increase strictly, a negative or non-finite `goal_tolerance`, and final
/// points with max_distance > goal_tolerance * extent (the message gives both numbers).
GoalSpread CheckDemonstrations(const DemoSet& set, double goal_tolerance);

/// Affine normalisation x_n = (x - offset) * scale (velocities: v_n = v * scale).
struct DemoNormalisation {
  Eigen::VectorXd offset;  ///< [d]
  double scale = 1;
};

/// offset = mean final point (the common goal); scale = half_range / max_{i,j} ||x_ij -
/// offset||_inf, so every normalised position lies in [-half_range, half_range]^d with the goal at
/// the origin. Error for half_range <= 0, an invalid set, or all positions at the goal.
DemoNormalisation FitNormalisation(const DemoSet& set, double half_range);

/// Positions (x - offset) * scale and velocities v * scale; time unchanged.
DemoSet ApplyNormalisation(const DemoSet& set, const DemoNormalisation& normalisation);

/// Keeps samples 0, stride, 2 stride, ... and always the last one; velocities and time stamps are
/// the source's at the kept samples (not recomputed). Error for stride < 1.
DemoSet Downsample(const DemoSet& set, int stride);

/// Fills every demo's velocity from its positions and time stamps: at interior samples the
/// three-point difference for unequal steps h- = t_j - t_j-1, h+ = t_j+1 - t_j,
///   v_j = (h-^2 (x_j+1 - x_j) + h+^2 (x_j - x_j-1)) / (h- h+ (h- + h+)),
/// exact for quadratics (the central difference (x_j+1 - x_j-1) / 2h for equal steps); the forward
/// difference at the first sample and zero at the last (the goal, where the system is at rest).
void FiniteDifferenceVelocities(DemoSet* set);

/// Splits by demonstration: the demos at `held_out` (in range, no duplicates, at least one left
/// for training) form the second set ("<name>:held_out"), the rest the first ("<name>:train"),
/// each in the original order.
std::pair<DemoSet, DemoSet> SplitByDemo(const DemoSet& set, const std::vector<int>& held_out);

/// The mean over demos of the point at arc-length fraction `fraction` in [0, 1] of each demo
/// (linear interpolation along the polyline; a demo of zero length contributes its first point).
/// Where to put an obstacle "on the demonstrations".
Eigen::VectorXd PointAlongDemos(const DemoSet& set, double fraction);

}  // namespace foresight
