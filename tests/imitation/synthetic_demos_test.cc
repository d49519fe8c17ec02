// Synthetic 2-D and task-space demonstrations: determinism, a common exact goal
// (CheckDemonstrations with a tight tolerance), closed forms of the noise-free curves, no
// self-intersection (brute force over segment pairs), velocities against finite differences (with
// second-order convergence), bounded accelerations and the JACO workspace box.

#include "datasets/synthetic_demos.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/test_util.h"

namespace foresight {
namespace {

using foresight::testing::ExpectErrorContains;

constexpr double kPi = 3.14159265358979323846;

/// Largest ||(x_j+1 - x_j-1) / (t_j+1 - t_j-1) - v_j|| over interior samples of all demos.
double WorstVelocityError(const DemoSet& set) {
  double worst = 0;
  for (const Demonstration& d : set.demos)
    for (int j = 1; j + 1 < d.points(); ++j) {
      const Eigen::VectorXd fd =
          (d.position.col(j + 1) - d.position.col(j - 1)) / (d.time(j + 1) - d.time(j - 1));
      worst = std::max(worst, (fd - d.velocity.col(j)).norm());
    }
  return worst;
}

/// Largest second difference of positions / dt^2 (all demos are uniform in time).
double MaxAcceleration(const DemoSet& set) {
  double worst = 0;
  for (const Demonstration& d : set.demos) {
    const double dt = d.time(1) - d.time(0);
    for (int j = 1; j + 1 < d.points(); ++j)
      worst = std::max(
          worst, (d.position.col(j + 1) - 2 * d.position.col(j) + d.position.col(j - 1)).norm() /
                     (dt * dt));
  }
  return worst;
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

/// Whether segments [p, q] and [r, s] properly intersect (orientation test).
bool SegmentsCross(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r,
                   const Eigen::Vector2d& s) {
  const double d1 = Cross(q - p, r - p), d2 = Cross(q - p, s - p);
  const double d3 = Cross(s - r, p - r), d4 = Cross(s - r, q - r);
  return d1 * d2 < 0 && d3 * d4 < 0;
}

bool SelfIntersects(const Eigen::MatrixXd& path) {
  for (Eigen::Index i = 0; i + 1 < path.cols(); ++i)
    for (Eigen::Index j = i + 2; j + 1 < path.cols(); ++j)
      if (SegmentsCross(path.col(i), path.col(i + 1), path.col(j), path.col(j + 1))) return true;
  return false;
}

bool SameSet(const DemoSet& a, const DemoSet& b) {
  if (a.demos.size() != b.demos.size()) return false;
  for (std::size_t i = 0; i < a.demos.size(); ++i)
    if (a.demos[i].position != b.demos[i].position || a.demos[i].velocity != b.demos[i].velocity ||
        a.demos[i].time != b.demos[i].time)
      return false;
  return true;
}

TEST(SyntheticDemos2d, EveryShapeIsValidSmoothAndDeterministic) {
  for (const std::string& shape : SyntheticShapes()) {
    SyntheticDemoConfig c;
    c.shape = shape;
    const DemoSet set = SyntheticDemos2d(c);
    EXPECT_EQ(set.name, shape);
    ASSERT_EQ(set.demos.size(), 7u);
    const GoalSpread spread = CheckDemonstrations(set, 1e-12);
    EXPECT_EQ(spread.goal, Eigen::Vector2d::Zero()) << shape;
    EXPECT_GT(spread.extent, 0.9) << shape;
    for (std::size_t i = 0; i < set.demos.size(); ++i) {
      const Demonstration& d = set.demos[i];
      EXPECT_EQ(d.points(), 200);
      EXPECT_EQ(d.position.col(199), Eigen::Vector2d::Zero());
      EXPECT_EQ(d.velocity.col(199), Eigen::Vector2d::Zero());
      EXPECT_GT(d.velocity.col(0).norm(), 0.1) << shape << " demo " << i << " starts at rest";
      EXPECT_NEAR(d.time(199), 5.0, 5.0 * c.noise + 1e-12);
      EXPECT_FALSE(SelfIntersects(d.position)) << shape << " demo " << i;
    }
    // Demos differ from each other, the same seed repeats, another seed differs.
    EXPECT_GT((set.demos[0].position - set.demos[1].position).cwiseAbs().maxCoeff(), 1e-3);
    EXPECT_TRUE(SameSet(set, SyntheticDemos2d(c))) << shape;
    SyntheticDemoConfig other = c;
    other.seed = 2;
    EXPECT_FALSE(SameSet(set, SyntheticDemos2d(other))) << shape;

    // Velocities: central differences converge to them at second order (x4 points: /16 error
    // with a 1/4 step... here 2x points: about /4).
    SyntheticDemoConfig fine = c;
    fine.points = 399;  // half the time step
    const double coarse_err = WorstVelocityError(set),
                 fine_err = WorstVelocityError(SyntheticDemos2d(fine));
    const double speed = set.demos[0].velocity.colwise().norm().maxCoeff();
    EXPECT_LT(coarse_err, 0.03 * speed) << shape;
    EXPECT_GT(coarse_err / fine_err, 3.5) << shape;
    EXPECT_LT(coarse_err / fine_err, 4.5) << shape;
    // Bounded accelerations that do not grow with resolution (no kinks).
    const double acc = MaxAcceleration(set), acc_fine = MaxAcceleration(SyntheticDemos2d(fine));
    EXPECT_LT(acc, 30.0) << shape;
    EXPECT_NEAR(acc_fine / acc, 1.0, 0.05) << shape;
  }
}

TEST(SyntheticDemos2d, NoiseFreeDemosFollowTheBaseCurve) {
  SyntheticDemoConfig c;
  c.noise = 0;
  c.demos = 2;
  c.shape = "arc";
  const DemoSet arc = SyntheticDemos2d(c);
  EXPECT_EQ(arc.demos[0].position, arc.demos[1].position);
  for (int j = 0; j < arc.demos[0].points(); ++j) {
    // A unit circle around (-1, 0) (the arc ends at (1, 0) before the shift to the goal).
    EXPECT_NEAR((arc.demos[0].position.col(j) + Eigen::Vector2d(1, 0)).norm(), 1.0, 1e-12);
    // Tangent velocity.
    EXPECT_NEAR(
        arc.demos[0].velocity.col(j).dot(arc.demos[0].position.col(j) + Eigen::Vector2d(1, 0)), 0.0,
        1e-12);
  }
  c.shape = "s_curve";
  const Demonstration s = SyntheticDemos2d(c).demos[0];
  for (int j = 0; j < s.points(); ++j) {
    const double param = 1 - s.position(1, j);  // y = 1 - s
    EXPECT_NEAR(s.position(0, j), 0.5 * std::cos(3 * kPi * param) + 0.5, 1e-12);
  }
  c.shape = "zigzag";
  const Demonstration z = SyntheticDemos2d(c).demos[0];
  for (int j = 0; j < z.points(); ++j) {
    const double param = z.position(0, j) + 1;  // x = s - 1
    EXPECT_NEAR(z.position(1, j), 0.6 / kPi * std::asin(0.95 * std::sin(3 * kPi * param)), 1e-12);
  }
  EXPECT_NEAR(z.position(0, 0), -1.0, 1e-15);
}

TEST(SyntheticDemos2d, RefusesBadConfigs) {
  SyntheticDemoConfig c;
  c.shape = "spiral";
  ExpectErrorContains([&] { SyntheticDemos2d(c); },
                      {"unknown shape 'spiral'", "arc, s_curve, zigzag"});
  c = SyntheticDemoConfig();
  c.points = 2;
  ExpectErrorContains([&] { SyntheticDemos2d(c); }, {"points must be >= 3", "2"});
  c = SyntheticDemoConfig();
  c.demos = 0;
  ExpectErrorContains([&] { SyntheticDemos2d(c); }, {"demos must be >= 1"});
  c = SyntheticDemoConfig();
  c.noise = -0.1;
  ExpectErrorContains([&] { SyntheticDemos2d(c); }, {"noise", "-0.1"});
}

TEST(TaskSpaceDemos, ReachableSmoothAndConvergent) {
  for (const std::string& task : TaskSpaceTasks()) {
    const int count = task == "push_box" ? kPushBoxDemos : kLiftBoxDemos;
    const DemoSet set = TaskSpaceDemos(task, count, 11);
    EXPECT_EQ(set.name, task);
    EXPECT_EQ(set.dimension, 3);
    ASSERT_EQ(static_cast<int>(set.demos.size()), count);
    const GoalSpread spread = CheckDemonstrations(set, 1e-12);
    EXPECT_LT(spread.max_distance, 1e-15) << task;  // the mean of equal points, rounded
    EXPECT_TRUE(SameSet(set, TaskSpaceDemos(task, count, 11))) << task;
    EXPECT_FALSE(SameSet(set, TaskSpaceDemos(task, count, 12))) << task;
    for (std::size_t i = 0; i < set.demos.size(); ++i) {
      const Demonstration& d = set.demos[i];
      EXPECT_EQ(d.points(), kPointsPerTaskDemo);
      EXPECT_GE(d.time(d.points() - 1), 4.0);
      EXPECT_LE(d.time(d.points() - 1), 6.0);
      const Eigen::VectorXd horizontal = d.position.topRows(2).colwise().norm();
      EXPECT_GE(horizontal.minCoeff(), 0.3) << task << " demo " << i;
      EXPECT_LE(horizontal.maxCoeff(), 0.75) << task << " demo " << i;
      EXPECT_GE(d.position.row(2).minCoeff(), 0.08) << task << " demo " << i;
      EXPECT_LE(d.position.row(2).maxCoeff(), 0.6) << task << " demo " << i;
      EXPECT_LT(d.velocity.col(0).norm(), 1e-12) << "starts at rest";
      EXPECT_EQ(d.velocity.col(d.points() - 1), Eigen::Vector3d::Zero());
      // Demos start several cm apart.
      if (i > 0) {
        EXPECT_GT((d.position.col(0) - set.demos[0].position.col(0)).norm(), 0.005);
      }
      // Task structure: the lowest point is at table / box height; push_box then moves
      // horizontally, lift_box then mostly upward.
      Eigen::Index low = 0;
      const double z_low = d.position.row(2).minCoeff(&low);
      EXPECT_NEAR(z_low, 0.12, 0.03) << task << " demo " << i;
      const Eigen::Vector3d after = d.position.col(d.points() - 1) - d.position.col(low);
      if (task == "push_box") {
        // The last quarter pushes: at table height, mostly horizontal.
        const int q = d.points() / 4;
        const Eigen::MatrixXd tail = d.position.rightCols(q);
        EXPECT_LT(tail.row(2).maxCoeff(), 0.14) << "pushing at table height";
        const double z_range = tail.row(2).maxCoeff() - tail.row(2).minCoeff();
        EXPECT_GT((tail.col(q - 1) - tail.col(0)).head<2>().norm(), 4 * z_range);
      } else {
        EXPECT_GT(after.z(), 0.3);
        EXPECT_GT(after.z(), 2 * after.head<2>().norm());
      }
    }
    const double err = WorstVelocityError(set);
    const double speed = set.demos[0].velocity.colwise().norm().maxCoeff();
    EXPECT_LT(err, 0.01 * speed) << task;
    EXPECT_LT(MaxAcceleration(set), 1.0) << task << " (m/s^2)";
  }
  ExpectErrorContains([] { TaskSpaceDemos("pour", 3, 1); },
                      {"unknown task 'pour'", "lift_box, push_box"});
  ExpectErrorContains([] { TaskSpaceDemos("push_box", 0, 1); }, {"demos must be >= 1"});
}

}  // namespace
}  // namespace foresight
