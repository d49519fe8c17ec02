// Demonstration sets: every refusal of CheckDemonstrations, the goal spread of a constructed set,
// normalisation bounds, splitting, downsampling, finite-difference velocities (exact on quadratics
// with uneven steps) and points along straight-line demos (closed form).

#include "datasets/demonstrations.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/test_util.h"

namespace foresight {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::MatricesNear;

/// A straight demo from `start` to `end` in n equal steps of dt, constant velocity (zero at the
/// end).
Demonstration Line(const Eigen::VectorXd& start, const Eigen::VectorXd& end, int n,
                   double dt = 0.1) {
  Demonstration d;
  d.position.resize(start.size(), n);
  d.velocity.resize(start.size(), n);
  d.time.resize(n);
  for (int j = 0; j < n; ++j) {
    const double u = static_cast<double>(j) / (n - 1);
    d.position.col(j) = (1 - u) * start + u * end;
    d.velocity.col(j) = (end - start) / ((n - 1) * dt);
    d.time(j) = j * dt;
  }
  d.velocity.col(n - 1).setZero();
  return d;
}

/// Three 2-D lines converging to (1, 1): from (-3, 1), (1, 5) and (1, -1).
DemoSet ThreeLines() {
  DemoSet set;
  set.name = "lines";
  set.dimension = 2;
  set.demos.push_back(Line(Eigen::Vector2d(-3, 1), Eigen::Vector2d(1, 1), 11));
  set.demos.push_back(Line(Eigen::Vector2d(1, 5), Eigen::Vector2d(1, 1), 21));
  set.demos.push_back(Line(Eigen::Vector2d(1, -1), Eigen::Vector2d(1, 1), 5));
  return set;
}

TEST(CheckDemonstrations, SpreadOfAConstructedSet) {
  DemoSet set = ThreeLines();
  GoalSpread s = CheckDemonstrations(set, 0.0);
  EXPECT_TRUE(MatricesNear(s.goal, Eigen::Vector2d(1, 1), 1e-15));
  EXPECT_EQ(s.max_distance, 0.0);
  EXPECT_DOUBLE_EQ(s.extent, 6.0);  // x in [-3, 1] (4), y in [-1, 5] (6)

  // Move the end of demo 2 by (0.3, 0): goal = (1.1, 1); farthest end 0.2 from it.
  set.demos[2].position(0, 4) += 0.3;
  s = CheckDemonstrations(set, 0.2 / 6.0 + 1e-9);
  EXPECT_TRUE(MatricesNear(s.goal, Eigen::Vector2d(1.1, 1), 1e-15));
  EXPECT_NEAR(s.max_distance, 0.2, 1e-15);
  ExpectErrorContains([&] { CheckDemonstrations(set, 0.03); },
                      {"'lines'", "demo 2", "0.2", "goal_tolerance 0.03", "extent 6"});
}

TEST(CheckDemonstrations, RefusesEachBadInput) {
  const DemoSet good = ThreeLines();
  DemoSet s;
  s = good;
  s.demos.clear();
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"'lines'", "no demonstrations"});
  s = good;
  s.dimension = 3;
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"'lines'", "demo 0", "2 rows"});
  s = good;
  s.demos[1] = Line(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), 4);
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"demo 1", "3 rows"});
  s = good;
  s.demos[2] = Line(Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 1), 2);
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"demo 2", "2 points"});
  s = good;
  s.demos[1].time.conservativeResize(20);
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"demo 1", "20 time stamps", "21"});
  s = good;
  s.demos[0].velocity.conservativeResize(2, 10);
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"demo 0", "velocity is [2 x 10]"});
  s = good;
  s.demos[0].velocity.resize(0, 0);
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); },
                      {"demo 0", "no velocities", "FiniteDifferenceVelocities"});
  s = good;
  s.demos[1].position(1, 3) = NAN;
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"demo 1", "non-finite position"});
  s = good;
  s.demos[2].velocity(0, 1) = INFINITY;
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"demo 2", "non-finite velocity"});
  s = good;
  s.demos[0].time(4) = NAN;
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); }, {"demo 0", "non-finite time"});
  s = good;
  s.demos[1].time(5) = s.demos[1].time(4);
  ExpectErrorContains([&] { CheckDemonstrations(s, 0.1); },
                      {"demo 1", "time does not increase at sample 5"});
  ExpectErrorContains([&] { CheckDemonstrations(good, -1); }, {"goal_tolerance", "-1"});
}

TEST(Normalisation, PositionsWithinHalfRangeGoalAtOrigin) {
  const DemoSet set = ThreeLines();
  const DemoNormalisation n = FitNormalisation(set, 0.5);
  EXPECT_TRUE(MatricesNear(n.offset, Eigen::Vector2d(1, 1), 1e-15));
  EXPECT_DOUBLE_EQ(n.scale,
                   0.5 / 4.0);  // farthest coordinate from the goal: |-3 - 1| = |5 - 1| = 4
  const DemoSet out = ApplyNormalisation(set, n);
  double largest = 0;
  for (std::size_t i = 0; i < out.demos.size(); ++i) {
    const Demonstration& d = out.demos[i];
    largest = std::max(largest, d.position.cwiseAbs().maxCoeff());
    EXPECT_LT(d.position.col(d.points() - 1).norm(), 1e-15) << "demo " << i;
    EXPECT_TRUE(
        MatricesNear(d.position, (set.demos[i].position.colwise() - n.offset) * n.scale, 1e-15));
    EXPECT_TRUE(MatricesNear(d.velocity, set.demos[i].velocity * n.scale, 1e-15));
    EXPECT_EQ(d.time, set.demos[i].time);
  }
  EXPECT_DOUBLE_EQ(largest, 0.5);
  EXPECT_NO_THROW(CheckDemonstrations(out, 1e-12));

  ExpectErrorContains([&] { FitNormalisation(set, 0); }, {"half_range", "'lines'"});
  ExpectErrorContains(
      [&] {
        ApplyNormalisation(set, {Eigen::Vector3d::Zero(), 1.0});
      },
      {"offset has 3 entries", "dimension 2"});
  DemoSet still = set;
  for (Demonstration& d : still.demos) d.position.setConstant(2.0);
  ExpectErrorContains([&] { FitNormalisation(still, 1); }, {"every position is at the goal"});
}

TEST(SplitByDemo, HoldsOutTheListedDemos) {
  const DemoSet set = ThreeLines();
  const auto [train, test] = SplitByDemo(set, {2, 0});
  ASSERT_EQ(train.demos.size(), 1u);
  ASSERT_EQ(test.demos.size(), 2u);
  EXPECT_EQ(train.demos[0].points(), 21);
  EXPECT_EQ(test.demos[0].points(), 11);  // original order kept
  EXPECT_EQ(test.demos[1].points(), 5);
  EXPECT_EQ(train.dimension, 2);
  EXPECT_EQ(train.name, "lines:train");
  EXPECT_EQ(test.name, "lines:held_out");
  EXPECT_EQ(SplitByDemo(set, {}).first.demos.size(), 3u);
  ExpectErrorContains([&] { SplitByDemo(set, {3}); }, {"index 3", "out of range", "3 demos"});
  ExpectErrorContains([&] { SplitByDemo(set, {-1}); }, {"index -1", "out of range"});
  ExpectErrorContains([&] { SplitByDemo(set, {1, 1}); }, {"index 1", "twice"});
  ExpectErrorContains([&] { SplitByDemo(set, {0, 1, 2}); }, {"none to train"});
}

TEST(Downsample, KeepsEveryStrideAndTheLast) {
  const DemoSet set = ThreeLines();
  const DemoSet out = Downsample(set, 3);
  // 11 points -> 0 3 6 9 10; 21 -> 0 3 ... 18 20; 5 -> 0 3 4.
  ASSERT_EQ(out.demos.size(), 3u);
  EXPECT_EQ(out.demos[0].points(), 5);
  EXPECT_EQ(out.demos[1].points(), 8);
  EXPECT_EQ(out.demos[2].points(), 3);
  EXPECT_TRUE(MatricesNear(out.demos[0].time,
                           (Eigen::VectorXd(5) << 0, 0.3, 0.6, 0.9, 1.0).finished(), 1e-15));
  for (std::size_t i = 0; i < 3; ++i) {
    const Demonstration &a = out.demos[i], &b = set.demos[i];
    EXPECT_EQ(a.position.col(a.points() - 1), b.position.col(b.points() - 1));
    EXPECT_EQ(a.position.col(1), b.position.col(3));
    EXPECT_EQ(a.velocity.col(1), b.velocity.col(3));  // kept, not recomputed
  }
  EXPECT_NO_THROW(CheckDemonstrations(out, 0));
  const DemoSet same = Downsample(set, 1);
  EXPECT_EQ(same.demos[1].position, set.demos[1].position);
  // Stride 4 leaves 2 of the 5 points of demo 2.
  ExpectErrorContains([&] { Downsample(set, 4); }, {"stride 4", "demo 2", "'lines'"});
  ExpectErrorContains([&] { Downsample(set, 0); }, {"stride must be >= 1"});
}

TEST(FiniteDifferenceVelocities, ExactOnQuadraticsWithUnevenSteps) {
  DemoSet set;
  set.name = "quad";
  set.dimension = 2;
  Demonstration d;
  const int n = 9;
  d.time.resize(n);
  d.position.resize(2, n);
  for (int j = 0; j < n; ++j) {
    const double t = 0.1 * j + 0.02 * j * j;  // uneven, increasing
    d.time(j) = t;
    d.position(0, j) = 1 + 2 * t - 3 * t * t;
    d.position(1, j) = -t + 0.5 * t * t;
  }
  set.demos.push_back(d);
  FiniteDifferenceVelocities(&set);
  const Demonstration& r = set.demos[0];
  ASSERT_EQ(r.velocity.rows(), 2);
  ASSERT_EQ(r.velocity.cols(), n);
  for (int j = 1; j + 1 < n; ++j) {
    const double t = r.time(j);
    EXPECT_TRUE(MatricesNear(r.velocity.col(j), Eigen::Vector2d(2 - 6 * t, -1 + t), 1e-12))
        << "sample " << j;
  }
  // First: forward difference (the chord slope); last: zero.
  EXPECT_TRUE(MatricesNear(
      r.velocity.col(0), (r.position.col(1) - r.position.col(0)) / (r.time(1) - r.time(0)), 1e-15));
  EXPECT_EQ(r.velocity.col(n - 1), Eigen::Vector2d::Zero());
  EXPECT_NO_THROW(CheckDemonstrations(set, 1.0));
}

TEST(PointAlongDemos, StraightLines) {
  const DemoSet set = ThreeLines();
  // At fraction f, the demos are at (-3 + 4f, 1), (1, 5 - 4f), (1, -1 + 2f).
  for (double f : {0.0, 0.25, 0.6, 1.0}) {
    const Eigen::Vector2d expected((-3 + 4 * f + 1 + 1) / 3, (1 + 5 - 4 * f - 1 + 2 * f) / 3);
    EXPECT_TRUE(MatricesNear(PointAlongDemos(set, f), expected, 1e-12)) << "f = " << f;
  }
  // Unevenly sampled line with a repeated point: arc length, not index, decides.
  DemoSet uneven;
  uneven.name = "uneven";
  uneven.dimension = 1;
  Demonstration d;
  d.position.resize(1, 5);
  d.position << 0, 0.1, 0.1, 0.2, 1.0;
  d.time = Eigen::VectorXd::LinSpaced(5, 0, 1);
  uneven.demos.push_back(d);
  EXPECT_NEAR(PointAlongDemos(uneven, 0.5)(0), 0.5, 1e-15);
  ExpectErrorContains([&] { PointAlongDemos(set, 1.5); }, {"fraction", "1.5"});
}

}  // namespace
}  // namespace foresight
