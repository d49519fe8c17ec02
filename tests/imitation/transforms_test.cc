// Obstacle and bias transforms and their composition by the pull-back, against central finite
// differences, trajectories of the inner system, and the behaviours of thesis ch 8 (bending around
// an obstacle, bias toward a point).

#include "inference/imitation/transforms.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "models/imitation/occupancy_fit.h"
#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

template <int D>
Vec<D> RandomPoint(std::mt19937_64* rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  Vec<D> p;
  for (int a = 0; a < D; ++a) p[a] = u(*rng);
  return p;
}

template <int D>
Mat<D> FiniteDifferenceJacobian(const std::function<Vec<D>(const Vec<D>&)>& f, const Vec<D>& x,
                                double h = 1e-6) {
  Mat<D> j;
  for (int a = 0; a < D; ++a) {
    Vec<D> e = Vec<D>::Zero();
    e[a] = h;
    j.col(a) = (f(x + e) - f(x - e)) / (2 * h);
  }
  return j;
}

// 21 x 21 states over [-1, 1]^2, ~49 inside the cut-off, truncation 4.6e-9.
RbfGrid<2> Grid2() {
  RbfGridSpec<2> s;
  s.lower = Vec<2>(-1, -1);
  s.counts = {21, 21};
  s.spacing = 0.1;
  s.gamma = 120;
  s.cutoff_radius = 0.4;
  return RbfGrid<2>(s);
}

Eigen::MatrixXd RandomWeights(int m, int d, double scale, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd w(m, d);
  for (Eigen::Index i = 0; i < w.size(); ++i) w.data()[i] = scale * n01(rng);
  return w;
}

// A disc obstacle fitted from lattice samples (the pipeline's path).
OccupancyField<2> DiscField(const Vec<2>& centre, double radius) {
  Eigen::Matrix<double, 2, -1> points;
  std::vector<std::uint8_t> occupied;
  SampleObstacleOccupancy<2>([&](const Vec<2>& s) { return (s - centre).norm() - radius; },
                             Vec<2>(-1, -1), Vec<2>(1, 1), 0.04, &points, &occupied);
  return FitOccupancyField<2>(Grid2(), points, occupied, 0.3, "disc");
}

template <int D>
OccupancyField<D> RandomField(const RbfGrid<D>& grid, double scale, std::uint64_t seed) {
  return OccupancyField<D>(grid, RandomWeights(grid.size(), 1, scale, seed).col(0), -0.5);
}

// psi's Jacobian against central differences and its inverse round trip at 30 random points of
// [-0.7, 0.7]^2. @return the largest displacement |psi(y) - y|; with `other`, the largest distance
// between psi(y) and other(y) in *apart.
double CheckJacobianAndInverse(const ObstacleTransform<2>& psi, std::mt19937_64* rng,
                               const ObstacleTransform<2>* other = nullptr,
                               double* apart = nullptr) {
  auto ws = psi.MakeWorkspace();
  double moved = 0;
  for (int n = 0; n < 30; ++n) {
    const Vec<2> y = RandomPoint<2>(rng, -0.7, 0.7);
    Mat<2> j;
    const Vec<2> x = psi.Forward(y, ws.get(), &j);
    EXPECT_TRUE(testing::MatricesNear(x, psi.Forward(y, ws.get()), 0));
    const Mat<2> fd =
        FiniteDifferenceJacobian<2>([&](const Vec<2>& s) { return psi.Forward(s, ws.get()); }, y);
    EXPECT_TRUE(testing::MatricesNear(j, fd, 1e-6 * (1 + j.norm())));
    Vec<2> back;
    if (!psi.Inverse(x, ws.get(), &back)) {
      ADD_FAILURE() << "no inverse at " << x.transpose();
      continue;
    }
    EXPECT_LE((back - y).norm(), 1e-10);
    moved = std::max(moved, (x - y).norm());
    if (other) *apart = std::max(*apart, (x - other->Forward(y, ws.get())).norm());
  }
  return moved;
}

TEST(ObstacleTransform, JacobianAndInverse) {
  const OccupancyField<2> field = RandomField(Grid2(), 0.5, 1);
  const ObstacleTransform<2> psi(field, {0.02, 10});
  std::mt19937_64 rng(1);
  EXPECT_GT(CheckJacobianAndInverse(psi, &rng), 0.01);
  // 3-D as well.
  RbfGridSpec<3> s3;
  s3.lower = Vec<3>::Constant(-0.5);
  s3.counts = {11, 11, 11};
  s3.spacing = 0.1;
  s3.gamma = 150;
  s3.cutoff_radius = 0.35;
  const ObstacleTransform<3> psi3(RandomField(RbfGrid<3>(s3), 0.5, 2), {0.03, 8});
  auto ws3 = psi3.MakeWorkspace();
  for (int n = 0; n < 10; ++n) {
    const Vec<3> y = RandomPoint<3>(&rng, -0.3, 0.3);
    Mat<3> j;
    const Vec<3> x = psi3.Forward(y, ws3.get(), &j);
    const Mat<3> fd =
        FiniteDifferenceJacobian<3>([&](const Vec<3>& s) { return psi3.Forward(s, ws3.get()); }, y);
    EXPECT_TRUE(testing::MatricesNear(j, fd, 1e-6 * (1 + j.norm())));
    Vec<3> back;
    ASSERT_TRUE(psi3.Inverse(x, ws3.get(), &back));
    // Exact to the truncation level of the 3-D grid's gradient field (exp(-18.4) at the cut-off).
    EXPECT_LE((back - y).norm(), std::max(1e-10, 10 * 0.03 * psi3.discontinuity()));
  }
}

// Through a tabulated map (OccupancyField::Tabulate) the transform is the Euler map of the
// interpolated field: its Jacobian is still exact (central differences), its inverse still
// round-trips, and it stays within the table's error of the transform on the exact map.
TEST(ObstacleTransform, ATabulatedMapKeepsAnExactJacobianAndInverse) {
  const OccupancyField<2> exact = RandomField(Grid2(), 0.5, 1);
  OccupancyField<2> table = exact;
  table.Tabulate(0.004);  // sigma = 1 / sqrt(240) = 0.065: about sigma / 16
  const ObstacleTransform<2> psi(table, {0.02, 10}), psi_exact(exact, {0.02, 10});
  std::mt19937_64 rng(8);
  double apart = 0;
  const double moved = CheckJacobianAndInverse(psi, &rng, &psi_exact, &apart);
  EXPECT_GT(moved, 0.01);
  EXPECT_LT(apart, 1e-4 * moved);
}

// The goal gate: psi_o fixes the goal exactly, the gated field's Jacobian and the transform's
// match central differences, and the inverse round-trips.
TEST(ObstacleTransform, GoalGateFixesTheGoalAndItsJacobiansMatch) {
  const OccupancyField<2> field = RandomField(Grid2(), 0.5, 6);
  const Vec<2> goal(0.1, -0.2);
  const ObstacleTransform<2> psi(field, {0.02, 10}, {goal, 0.15});
  auto ws = psi.MakeWorkspace();
  Mat<2> j;
  EXPECT_TRUE(testing::MatricesNear(psi.Forward(goal, ws.get(), &j), goal, 0));
  EXPECT_TRUE(testing::MatricesNear(j, Mat<2>::Identity(), 0));
  const ObstacleTransform<2> open(field, {0.02, 10});
  EXPECT_GT((open.Forward(goal, ws.get()) - goal).norm(), 1e-4) << "the ungated map moves it";
  std::mt19937_64 rng(7);
  for (int n = 0; n < 20; ++n) {
    const Vec<2> y = RandomPoint<2>(&rng, -0.5, 0.5);
    Mat<2> dv;
    psi.Field(y, ws.get(), &dv);
    const Mat<2> dv_fd =
        FiniteDifferenceJacobian<2>([&](const Vec<2>& s) { return psi.Field(s, ws.get()); }, y);
    EXPECT_TRUE(testing::MatricesNear(dv, dv_fd, 1e-6 * (1 + dv.norm())));
    const Vec<2> x = psi.Forward(y, ws.get(), &j);
    // A step of 1e-7: this random map curves sharply (1e-6 leaves a 2e-5 difference error).
    const Mat<2> fd = FiniteDifferenceJacobian<2>(
        [&](const Vec<2>& s) { return psi.Forward(s, ws.get()); }, y, 1e-7);
    EXPECT_TRUE(testing::MatricesNear(j, fd, 1e-6 * (1 + j.norm()))) << y.transpose();
    Vec<2> back;
    ASSERT_TRUE(psi.Inverse(x, ws.get(), &back));
    EXPECT_LE((back - y).norm(), 1e-10);
  }
  testing::ExpectErrorContains(
      [&] {
        ObstacleTransform<2>(field, {0.02, 10}, {goal, -1});
      },
      {"goal gate", "-1"});
}

// Forward stops once the field is exactly zero (no feature within the cut-off): the result must
// equal every Euler step taken, with the same values, inside and outside the map's support.
TEST(ObstacleTransform, StoppingOutsideTheSupportGivesTheFullFlowExactly) {
  RbfGridSpec<2> spec;  // the map covers [-0.3, 0.3]^2; support ends 0.4 beyond
  spec.lower = Vec<2>(-0.3, -0.3);
  spec.counts = {7, 7};
  spec.spacing = 0.1;
  spec.gamma = 120;
  spec.cutoff_radius = 0.4;
  const ObstacleTransform<2> psi(RandomField(RbfGrid<2>(spec), 0.5, 3), {0.05, 25});
  auto ws = psi.MakeWorkspace();
  const double h = 0.05 / 25;
  std::mt19937_64 rng(4);
  int outside = 0, inside = 0;
  for (int n = 0; n < 200; ++n) {
    const Vec<2> y = RandomPoint<2>(&rng, -1.2, 1.2);
    Vec<2> s = y;  // every step
    Mat<2> j = Mat<2>::Identity();
    OccupancyValue<2> v;
    for (int k = 0; k < 25; ++k) {
      psi.field().Evaluate(s, ws.get(), true, &v);
      j = (Mat<2>::Identity() + h * v.hessian) * j;
      s += h * v.gradient;
    }
    Mat<2> jacobian;
    const Vec<2> x = psi.Forward(y, ws.get(), &jacobian);
    EXPECT_TRUE(testing::MatricesNear(x, s, 0)) << y.transpose();
    EXPECT_TRUE(testing::MatricesNear(jacobian, j, 0)) << y.transpose();
    EXPECT_TRUE(testing::MatricesNear(psi.Forward(y, ws.get()), s, 0)) << y.transpose();
    psi.field().Evaluate(y, ws.get(), false, &v);
    (v.gradient.isZero(0) ? outside : inside) += 1;
  }
  EXPECT_GT(outside, 20);
  EXPECT_GT(inside, 20);
}

ImitationSystem<2> RandomImitation(double scale, std::uint64_t seed, const Vec<2>& goal) {
  const RbfGrid<2> grid = Grid2();
  return ImitationSystem<2>(RbfFlow<2>(grid, RandomWeights(grid.size(), 2, scale, seed), {1.0, 10}),
                            goal, 1.0);
}

TEST(ComposedSystem, VelocityIsThePullBack) {
  const ImitationSystem<2> inner = RandomImitation(0.05, 3, Vec<2>(0.5, 0.1));
  OuterTransform<2> obstacle;
  obstacle.type = OuterTransform<2>::Type::kObstacle;
  obstacle.obstacle = ObstacleTransform<2>(DiscField(Vec<2>(0, 0), 0.25), {0.05, 10});
  OuterTransform<2> bias;
  bias.type = OuterTransform<2>::Type::kBias;
  bias.bias = RbfFlow<2>(Grid2(), RandomWeights(Grid2().size(), 2, 0.05, 4), {0.5, 5});
  // One obstacle transform.
  const ComposedSystem<2> one(inner, {obstacle});
  // Obstacle innermost (psi_1), bias outermost (psi_2): x = psi_1(psi_2(y)).
  const ComposedSystem<2> two(inner, {obstacle, bias});
  ComposedWorkspace<2> ws1 = one.MakeWorkspace(), ws2 = two.MakeWorkspace();
  auto obstacle_ws = obstacle.obstacle.MakeWorkspace();
  FlowWorkspace<2> bias_ws = bias.bias.MakeWorkspace(), inner_ws = inner.flow().MakeWorkspace();
  const auto psi_o = [&](const Vec<2>& y) {
    return obstacle.obstacle.Forward(y, obstacle_ws.get());
  };
  const auto psi_b = [&](const Vec<2>& y) { return bias.bias.Forward(y, &bias_ws); };
  std::mt19937_64 rng(3);
  double bend = 0;
  for (int n = 0; n < 30; ++n) {
    const Vec<2> y = RandomPoint<2>(&rng, -0.6, 0.6);
    const Mat<2> jo = FiniteDifferenceJacobian<2>(psi_o, y);
    const Vec<2> expected = jo.inverse() * inner.Velocity(psi_o(y), &inner_ws);
    const Vec<2> v = one.Velocity(y, &ws1);
    EXPECT_TRUE(testing::MatricesNear(v, expected, 1e-6 * (1 + expected.norm()))) << y.transpose();
    EXPECT_TRUE(testing::MatricesNear(one.Inner(y, &ws1), psi_o(y), 0));
    bend = std::max(bend, (v - inner.Velocity(y, &inner_ws)).norm());
    // Two transforms: (J_1(psi_2(y)) J_2(y))^-1 f_i(psi_1(psi_2(y))).
    const Vec<2> yb = psi_b(y);
    const Mat<2> chain =
        FiniteDifferenceJacobian<2>(psi_o, yb) * FiniteDifferenceJacobian<2>(psi_b, y);
    // Compared through the chain (J v = f_i): the inverse of an ill-conditioned chain amplifies
    // the finite-difference error.
    const Vec<2> f = inner.Velocity(psi_o(yb), &inner_ws);
    EXPECT_TRUE(testing::MatricesNear(chain * two.Velocity(y, &ws2), f, 1e-6 * (1 + f.norm())));
    EXPECT_TRUE(testing::MatricesNear(two.Inner(y, &ws2), psi_o(yb), 0));
  }
  EXPECT_GT(bend, 0.1);  // the obstacle does change the velocity
  // No outer transforms: the imitation system itself.
  const ComposedSystem<2> none(inner, {});
  ComposedWorkspace<2> ws0 = none.MakeWorkspace();
  const Vec<2> y(0.3, -0.2);
  EXPECT_TRUE(testing::MatricesNear(none.Velocity(y, &ws0), inner.Velocity(y, &inner_ws), 0));
}

// RK4 step of y_dot = f(y).
Vec<2> Rk4(const std::function<Vec<2>(const Vec<2>&)>& f, const Vec<2>& y, double dt) {
  const Vec<2> k1 = f(y), k2 = f(y + 0.5 * dt * k1), k3 = f(y + 0.5 * dt * k2), k4 = f(y + dt * k3);
  return y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
}

TEST(ComposedSystem, TrajectoriesAreImagesOfTheInnerOnes) {
  const ImitationSystem<2> inner = RandomImitation(0.05, 5, Vec<2>(0.6, 0.0));
  OuterTransform<2> obstacle;
  obstacle.obstacle = ObstacleTransform<2>(DiscField(Vec<2>(0, 0.05), 0.25), {0.1, 20});
  const ComposedSystem<2> outer(inner, {obstacle});
  ComposedWorkspace<2> ws = outer.MakeWorkspace();
  FlowWorkspace<2> inner_ws = inner.flow().MakeWorkspace();
  Vec<2> y(-0.6, 0.1);
  Vec<2> x = outer.Inner(y, &ws);
  const double dt = 0.005;
  double worst = 0, gap = 0;
  for (int k = 0; k < 100; ++k) {  // 0.5 time units, away from the goal
    y = Rk4([&](const Vec<2>& s) { return outer.Velocity(s, &ws); }, y, dt);
    x = Rk4([&](const Vec<2>& s) { return inner.Velocity(s, &inner_ws); }, x, dt);
    worst = std::max(worst, (outer.Inner(y, &ws) - x).norm());
    gap = std::max(gap, (y - x).norm());
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(gap, 0.01);  // y and x differ: the check is not trivial
}

// Zero weights: psi_i = id and f_i is the plain attractor -speed (x - g) / ||x - g||.
ImitationSystem<2> Attractor(const Vec<2>& goal) {
  const RbfGrid<2> grid = Grid2();
  return ImitationSystem<2>(RbfFlow<2>(grid, Eigen::MatrixXd::Zero(grid.size(), 2), {1.0, 10}),
                            goal, 1.0);
}

TEST(ComposedSystem, BendsAroundAnObstacleAndReachesTheGoal) {
  const Vec<2> start(-0.8, 0.0), goal(0.8, 0.05), centre(0, 0);
  const ImitationSystem<2> inner = Attractor(goal);
  const OccupancyField<2> field = DiscField(centre, 0.25);
  auto fws = field.MakeWorkspace();
  RolloutSettings settings;
  settings.dt = 0.01;
  settings.max_steps = 1000;
  settings.goal_tolerance = 0.02;
  // Without the transform the straight path crosses the obstacle.
  FlowWorkspace<2> iws = inner.flow().MakeWorkspace();
  const Rollout<2> straight =
      RollOut<2>([&](const Vec<2>& x) { return inner.Velocity(x, &iws); }, start, goal, settings);
  ASSERT_TRUE(straight.reached);
  double p_straight = 0;
  for (Eigen::Index k = 0; k < straight.path.cols(); ++k)
    p_straight = std::max(p_straight, field.Probability(straight.path.col(k), fws.get()));
  EXPECT_GT(p_straight, 0.9);

  OuterTransform<2> obstacle;
  obstacle.obstacle = ObstacleTransform<2>(field, {1.0, 50});
  const ComposedSystem<2> outer(inner, {obstacle});
  ComposedWorkspace<2> ws = outer.MakeWorkspace();
  // The outer system's goal: psi_o^-1(goal) (= goal where p is flat).
  Vec<2> outer_goal;
  ASSERT_TRUE(obstacle.obstacle.Inverse(goal, fws.get(), &outer_goal));
  EXPECT_LT((outer_goal - goal).norm(), 1e-3);
  const Rollout<2> bent = RollOut<2>([&](const Vec<2>& y) { return outer.Velocity(y, &ws); }, start,
                                     outer_goal, settings);
  EXPECT_TRUE(bent.reached);
  EXPECT_TRUE(bent.finite);
  double p_bent = 0;
  for (Eigen::Index k = 0; k < bent.path.cols(); ++k)
    p_bent = std::max(p_bent, field.Probability(bent.path.col(k), fws.get()));
  EXPECT_LT(p_bent, 0.5);
}

TEST(BiasTransform, PullsTheSystemTowardTheTarget) {
  const RbfGrid<2> grid = Grid2();
  const Vec<2> target(0.0, 0.35);
  Eigen::Matrix<double, 2, -1> samples(2, 0);
  std::vector<Vec<2>> list;
  for (double x = -0.8; x <= 0.8 + 1e-9; x += 0.05)
    for (double y = -0.4; y <= 0.8 + 1e-9; y += 0.05) list.emplace_back(x, y);
  samples.resize(2, static_cast<Eigen::Index>(list.size()));
  for (std::size_t i = 0; i < list.size(); ++i) samples.col(static_cast<Eigen::Index>(i)) = list[i];
  const RbfFlow<2> bias = FitBiasTransform<2>(grid, samples, target, 1e-3, {0.3, 10});
  FlowWorkspace<2> bws = bias.MakeWorkspace();
  double cosine = 0;
  for (Eigen::Index i = 0; i < samples.cols(); ++i) {
    const Vec<2> v = bias.Field(samples.col(i), &bws);
    const Vec<2> away = samples.col(i) - target;
    cosine += v.dot(away) / (v.norm() * away.norm());
  }
  cosine /= static_cast<double>(samples.cols());
  EXPECT_GT(cosine, 0.9);

  const Vec<2> start(-0.7, 0.0), goal(0.7, 0.0);
  const ImitationSystem<2> inner = Attractor(goal);
  OuterTransform<2> outer_bias;
  outer_bias.type = OuterTransform<2>::Type::kBias;
  outer_bias.bias = bias;
  const ComposedSystem<2> biased(inner, {outer_bias});
  ComposedWorkspace<2> ws = biased.MakeWorkspace();
  Vec<2> outer_goal;
  ASSERT_TRUE(bias.Inverse(goal, &bws, &outer_goal));
  RolloutSettings settings;
  settings.goal_tolerance = 0.02;
  const Rollout<2> r = RollOut<2>([&](const Vec<2>& y) { return biased.Velocity(y, &ws); }, start,
                                  outer_goal, settings);
  EXPECT_TRUE(r.reached);
  double closest = 1e9;
  for (Eigen::Index k = 0; k < r.path.cols(); ++k)
    closest = std::min(closest, (r.path.col(k) - target).norm());
  // The unbiased path is the segment y = 0: 0.35 from the target at best.
  EXPECT_LT(closest, 0.35 - 0.05);
  testing::ExpectErrorContains(
      [&] {
        FitBiasTransform<2>(grid, samples, target, 0, {1.0, 10});
      },
      {"ridge"});
}

}  // namespace
}  // namespace foresight::imitation
