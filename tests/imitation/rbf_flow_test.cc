// The RBF grid and the imitation flow against independent computations: brute-force loops over all
// inducing states, central finite differences, a dense re-implementation of f_i, and rollouts.

#include "inference/imitation/rbf_flow.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "inference/imitation/transforms.h"
#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

// A realistic 2-D grid (21 x 21 states over [-1, 1]^2, ~49 inside the cut-off) and 3-D grid, both
// with gamma cutoff^2 >= 18 (truncation <= 1.5e-8, rbf_grid.h).
RbfGridSpec<2> Grid2() {
  RbfGridSpec<2> s;
  s.lower = Vec<2>(-1, -1);
  s.counts = {21, 21};
  s.spacing = 0.1;
  s.gamma = 120;
  s.cutoff_radius = 0.4;
  return s;
}
RbfGridSpec<3> Grid3() {
  RbfGridSpec<3> s;
  s.lower = Vec<3>(-0.5, -0.4, -0.3);
  s.counts = {11, 9, 7};
  s.spacing = 0.1;
  s.gamma = 150;
  s.cutoff_radius = 0.35;
  return s;
}
// A coarse truncation (exp(-4.5) = 0.011 at the cut-off).
RbfGridSpec<2> CoarseGrid2() {
  RbfGridSpec<2> s = Grid2();
  s.gamma = 50;
  s.cutoff_radius = 0.3;
  return s;
}
// Grids whose cut-off covers every state for points in [-0.3, 0.3]^D: the features are smooth
// there, so finite differences never straddle a truncation.
template <int D>
RbfGridSpec<D> SmoothGrid() {
  RbfGridSpec<D> s;
  s.lower = Vec<D>::Constant(D == 2 ? -0.3 : -0.2);
  s.counts.fill(D == 2 ? 7 : 5);
  s.spacing = 0.1;
  s.gamma = 30;
  s.cutoff_radius = D == 2 ? 1.0 : 0.75;
  return s;
}

template <int D>
Eigen::MatrixXd RandomWeights(int m, double scale, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd w(m, D);
  for (Eigen::Index i = 0; i < w.size(); ++i) w.data()[i] = scale * n01(rng);
  return w;
}

template <int D>
Vec<D> RandomPoint(std::mt19937_64* rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  Vec<D> p;
  for (int a = 0; a < D; ++a) p[a] = u(*rng);
  return p;
}

// Independent centre of state t: t = i_0 + n_0 (i_1 + n_1 i_2).
template <int D>
Vec<D> BruteCentre(const RbfGridSpec<D>& g, int t) {
  Vec<D> c;
  c[0] = g.lower[0] + g.spacing * (t % g.counts[0]);
  c[1] = g.lower[1] + g.spacing * ((t / g.counts[0]) % g.counts[1]);
  if constexpr (D == 3) c[2] = g.lower[2] + g.spacing * (t / (g.counts[0] * g.counts[1]));
  return c;
}

template <int D>
int GridSize(const RbfGridSpec<D>& g) {
  int m = 1;
  for (int a = 0; a < D; ++a) m *= g.counts[a];
  return m;
}

// All features by brute force over every inducing state, with the cut-off.
template <int D>
Eigen::VectorXd BruteFeatures(const RbfGridSpec<D>& g, const Vec<D>& s) {
  const int m = GridSize(g);
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(m);
  for (int t = 0; t < m; ++t) {
    const double d = (s - BruteCentre(g, t)).norm();
    if (d <= g.cutoff_radius) phi[t] = std::exp(-g.gamma * d * d);
  }
  return phi;
}

template <int D>
void CheckFeaturesAgainstBruteForce(const RbfGridSpec<D>& spec, std::uint64_t seed) {
  const RbfGrid<D> grid(spec);
  ASSERT_EQ(grid.size(), GridSize(spec));
  for (int t = 0; t < grid.size(); t += 7)
    EXPECT_TRUE(testing::MatricesNear(grid.Centre(t), BruteCentre(spec, t), 1e-12)) << t;
  RbfFeatures<D> f;
  std::mt19937_64 rng(seed);
  int total = 0;
  for (int n = 0; n < 200; ++n) {
    // Inside, near the edges and beyond the grid.
    const Vec<D> s = RandomPoint<D>(&rng, -1.3, 1.3);
    grid.Evaluate(s, &f);
    Eigen::VectorXd sparse = Eigen::VectorXd::Zero(grid.size());
    for (int k = 0; k < f.count; ++k) {
      ASSERT_GE(f.index[k], 0);
      ASSERT_LT(f.index[k], grid.size());
      EXPECT_EQ(sparse[f.index[k]], 0.0) << "state listed twice";
      sparse[f.index[k]] = f.phi[k];
      EXPECT_TRUE(testing::MatricesNear(f.offset[k], s - BruteCentre(spec, f.index[k]), 1e-12));
      // The derivative the offset implies, -2 g phi r, against central differences of the
      // Gaussian exp(-g ||s - c||^2).
      const Vec<D> c = BruteCentre(spec, f.index[k]);
      Vec<D> fd;
      for (int a = 0; a < D; ++a) {
        Vec<D> e = Vec<D>::Zero();
        e[a] = 1e-6;
        fd[a] = (std::exp(-spec.gamma * (s + e - c).squaredNorm()) -
                 std::exp(-spec.gamma * (s - e - c).squaredNorm())) /
                2e-6;
      }
      EXPECT_TRUE(testing::MatricesNear(-2 * spec.gamma * f.phi[k] * f.offset[k], fd, 1e-8));
    }
    total += f.count;
    EXPECT_TRUE(testing::MatricesNear(sparse, BruteFeatures(spec, s), 1e-14)) << s.transpose();
  }
  EXPECT_GT(total, 200);  // the points do touch the grid
  // Non-finite and far points: no features.
  grid.Evaluate(Vec<D>::Constant(std::nan("")), &f);
  EXPECT_EQ(f.count, 0);
  grid.Evaluate(Vec<D>::Constant(1e300), &f);
  EXPECT_EQ(f.count, 0);
}

TEST(RbfGrid, FeaturesEqualBruteForce2D) { CheckFeaturesAgainstBruteForce(Grid2(), 1); }
TEST(RbfGrid, FeaturesEqualBruteForce3D) { CheckFeaturesAgainstBruteForce(Grid3(), 2); }

TEST(RbfGrid, CoveringAndBadSpecs) {
  const RbfGridSpec<2> c = RbfGrid<2>::Covering(Vec<2>(0, 1), Vec<2>(1, 1.55), 0.2, 0.1, 50, 0.3);
  EXPECT_TRUE(testing::MatricesNear(c.lower, Vec<2>(-0.2, 0.8), 1e-15));
  EXPECT_EQ(c.counts[0], 15);  // -0.2 .. 1.2
  EXPECT_EQ(c.counts[1], 11);  // 0.8 .. 1.8 covers 1.75
  EXPECT_GE(c.lower[1] + c.spacing * (c.counts[1] - 1), 1.75);
  RbfGridSpec<2> bad = Grid2();
  bad.spacing = 0;
  testing::ExpectErrorContains([&] { RbfGrid<2> g(bad, "my grid"); }, {"my grid", "spacing"});
  bad = Grid2();
  bad.counts[1] = 0;
  testing::ExpectErrorContains([&] { RbfGrid<2> g(bad); }, {"count", "axis 1"});
  bad = Grid2();
  bad.cutoff_radius = 2.0;  // 41 x 41 window > 1024
  testing::ExpectErrorContains([&] { RbfGrid<2> g(bad); }, {"cut-off window", "1681"});
  bad = Grid2();
  bad.gamma = std::nan("");
  testing::ExpectErrorContains([&] { RbfGrid<2> g(bad); }, {"gamma"});
  bad = Grid2();
  bad.gamma = 1e5;  // gamma spacing^2 = 1000: the factors' recurrence would underflow
  testing::ExpectErrorContains([&] { RbfGrid<2> g(bad); }, {"gamma spacing^2", "300"});
}

// The separable factors come from two exponentials per axis and a recurrence outward from the
// state nearest the point: each must still be exp(-gamma d^2) to 1e-13 (1 + gamma d^2) relative
// (the exponent's own rounding moves exp by about 1e-16 gamma d^2), also on a steep kernel
// (exp(-gamma h^2) = e^-8 per state), far out in the window, and beyond the grid.
TEST(RbfGrid, WindowFactorsAreTheExponentialsToRounding) {
  for (double gamma_h2 : {0.49, 8.0}) {
    RbfGridSpec<3> spec;
    spec.lower = Vec<3>(-1, -0.5, 0);
    spec.counts = {21, 11, 6};
    spec.spacing = 0.1;
    spec.gamma = gamma_h2 / (spec.spacing * spec.spacing);
    spec.cutoff_radius = 0.75;
    const RbfGrid<3> grid(spec);
    std::mt19937_64 rng(7);
    typename RbfGrid<3>::AxisWindows w;
    int checked = 0;
    for (int n = 0; n < 300; ++n) {
      const Vec<3> s = RandomPoint<3>(&rng, -1.5, 1.5);
      if (!grid.Windows(s, &w)) continue;
      for (int a = 0; a < 3; ++a)
        for (int i = 0; i < w.n[a]; ++i) {
          const double d = s[a] - (spec.lower[a] + spec.spacing * (w.first[a] + i));
          EXPECT_EQ(w.d[a][i], d);
          const double exact = std::exp(-spec.gamma * d * d);
          // Relative to the exponent's size: the rounding of gamma d^2 alone moves exp by that.
          EXPECT_NEAR(w.e[a][i], exact, 1e-13 * (1 + spec.gamma * d * d) * exact)
              << gamma_h2 << " axis " << a << " d " << d;
          ++checked;
        }
    }
    EXPECT_GT(checked, 1000);
  }
}

// ---- flow -------------------------------------------------------------------------------------

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

template <int D>
void CheckFlowJacobians(std::uint64_t seed) {
  const RbfGrid<D> grid(SmoothGrid<D>());
  const RbfFlow<D> flow(grid, RandomWeights<D>(grid.size(), 0.3, seed), {1.0, 10});
  FlowWorkspace<D> ws = flow.MakeWorkspace();
  std::mt19937_64 rng(seed);
  for (int n = 0; n < 10; ++n) {
    const Vec<D> x = RandomPoint<D>(&rng, -0.15, 0.15);
    Mat<D> dv, j;
    const Vec<D> v = flow.Field(x, &ws, &dv);
    EXPECT_TRUE(testing::MatricesNear(v, flow.Field(x, &ws), 0));
    const Mat<D> dv_fd =
        FiniteDifferenceJacobian<D>([&](const Vec<D>& s) { return flow.Field(s, &ws); }, x);
    EXPECT_TRUE(testing::MatricesNear(dv, dv_fd, 1e-6 * (1 + dv.norm())));
    EXPECT_GT(dv.norm(), 0.1);  // a non-trivial field
    const Vec<D> z = flow.Forward(x, &ws, &j);
    EXPECT_TRUE(testing::MatricesNear(z, flow.Forward(x, &ws), 0));
    const Mat<D> j_fd =
        FiniteDifferenceJacobian<D>([&](const Vec<D>& s) { return flow.Forward(s, &ws); }, x);
    EXPECT_TRUE(testing::MatricesNear(j, j_fd, 1e-6 * (1 + j.norm())));
    EXPECT_GT((j - Mat<D>::Identity()).norm(), 0.05);
  }
}

TEST(RbfFlow, JacobiansMatchFiniteDifferences2D) { CheckFlowJacobians<2>(3); }
TEST(RbfFlow, JacobiansMatchFiniteDifferences3D) { CheckFlowJacobians<3>(4); }

template <int D>
void CheckRoundTrip(const RbfGridSpec<D>& spec, double scale, std::uint64_t seed) {
  const RbfGrid<D> grid(spec);
  for (int trial = 0; trial < 3; ++trial) {
    const RbfFlow<D> flow(grid, RandomWeights<D>(grid.size(), scale, seed + trial), {1.0, 10});
    FlowWorkspace<D> ws = flow.MakeWorkspace();
    std::mt19937_64 rng(seed + trial);
    double moved = 0;
    for (int n = 0; n < 50; ++n) {
      const Vec<D> x = RandomPoint<D>(&rng, -0.6, 0.6);
      const Vec<D> z = flow.Forward(x, &ws);
      moved = std::max(moved, (z - x).norm());
      Vec<D> back;
      ASSERT_TRUE(flow.Inverse(z, &ws, &back));
      EXPECT_LE((back - x).norm(), 1e-10) << x.transpose();
    }
    EXPECT_GT(moved, 0.05);  // the flow does deform
  }
}

TEST(RbfFlow, InverseUndoesForward2D) { CheckRoundTrip(Grid2(), 0.08, 10); }
TEST(RbfFlow, InverseUndoesForward3D) { CheckRoundTrip(Grid3(), 0.05, 20); }

// With a coarse cut-off the Euler map has no exact inverse near cut-off circles; Inverse still
// converges and is exact to the truncation level.
TEST(RbfFlow, CoarseTruncationInverseWithinItsBound) {
  const RbfGrid<2> grid(CoarseGrid2());
  const RbfFlow<2> flow(grid, RandomWeights<2>(grid.size(), 0.08, 13), {1.0, 10});
  EXPECT_NEAR(flow.discontinuity(), 2 * std::exp(-4.5) * flow.weights().rowwise().norm().maxCoeff(),
              1e-15);
  FlowWorkspace<2> ws = flow.MakeWorkspace();
  std::mt19937_64 rng(13);
  double worst = 0;
  for (int n = 0; n < 200; ++n) {
    const Vec<2> x = RandomPoint<2>(&rng, -0.6, 0.6);
    Vec<2> back;
    ASSERT_TRUE(flow.Inverse(flow.Forward(x, &ws), &ws, &back));
    worst = std::max(worst, (back - x).norm());
  }
  EXPECT_LE(worst, 10 * flow.settings().time * flow.discontinuity());
  EXPECT_GT(worst, 1e-10);  // the truncation is visible: this is why grids keep it small
}

TEST(RbfFlow, NonInvertibleSettingsAreDetected) {
  const RbfGrid<2> grid(Grid2());
  const Eigen::MatrixXd w = RandomWeights<2>(grid.size(), 2.0, 5);
  Eigen::Matrix<double, 2, -1> points(2, 121);
  for (int i = 0; i < 121; ++i)
    points.col(i) = Vec<2>(-0.5 + 0.1 * (i % 11), -0.5 + 0.1 * (i / 11));
  // Large weights, long time, few steps: h Lip(V) >> 1.
  const RbfFlow<2> bad(grid, w, {3.0, 2});
  FlowWorkspace<2> ws = bad.MakeWorkspace();
  int failed = 0;
  for (int i = 0; i < points.cols(); ++i) {
    Vec<2> back;
    const bool ok = bad.Inverse(bad.Forward(points.col(i), &ws), &ws, &back);
    if (!ok || (back - points.col(i)).norm() > 1e-8) ++failed;
  }
  EXPECT_GT(failed, 10);
  const InvertibilityReport report = CheckInvertible(bad, points, 1e-8);
  EXPECT_FALSE(report.ok);
  EXPECT_EQ(report.points, 121);
  EXPECT_TRUE(report.failed_points > 0 || report.max_roundtrip_error > 1e-8);
  EXPECT_LT(report.min_step_determinant, 0);
  const std::string text = report.Describe();
  EXPECT_NE(text.find("NOT invertible"), std::string::npos) << text;
  EXPECT_NE(text.find("determinant"), std::string::npos) << text;
  EXPECT_NE(text.find(std::to_string(report.failed_points) + " points"), std::string::npos) << text;
  // The same weights scaled down, with more steps, are invertible.
  const RbfFlow<2> good(grid, w * 0.02, {1.0, 10});
  const InvertibilityReport fine = CheckInvertible(good, points, 1e-9);
  EXPECT_TRUE(fine.ok) << fine.Describe();
  EXPECT_GT(fine.min_step_determinant, 0);
  EXPECT_EQ(fine.failed_points, 0);
}

TEST(RbfFlow, BadInputIsAnError) {
  const RbfGrid<2> grid(Grid2());
  testing::ExpectErrorContains(
      [&] {
        RbfFlow<2> f(grid, Eigen::MatrixXd::Zero(grid.size(), 3), {1.0, 10}, "flow x");
      },
      {"flow x", "441 x 2"});
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(grid.size(), 2);
  w(3, 1) = std::nan("");
  testing::ExpectErrorContains([&] { RbfFlow<2> f(grid, w, {1.0, 10}); }, {"not finite"});
  testing::ExpectErrorContains(
      [&] {
        RbfFlow<2> f(grid, Eigen::MatrixXd::Zero(grid.size(), 2), {1.0, 0});
      },
      {"steps"});
  const RbfFlow<2> f(grid, Eigen::MatrixXd::Zero(grid.size(), 2), {1.0, 10});
  testing::ExpectErrorContains([&] { ImitationSystem<2> s(f, Vec<2>(0, 0), -1); }, {"speed"});
}

// ---- time segments -----------------------------------------------------------------------------

// A flow of S segments is the composition of S one-segment flows, segment g with its own weights,
// time T / S and K / S steps (when S divides K): psi = psi_{S-1} o ... o psi_0, and the Jacobian is
// the product of theirs in the same order (the chain rule).
template <int D>
void CheckSegmentsCompose(const RbfGridSpec<D>& spec, double scale, std::uint64_t seed) {
  const RbfGrid<D> grid(spec);
  const int segments = 3, steps = 12, m = grid.size();
  const Eigen::MatrixXd w = RandomWeights<D>(segments * m, scale, seed);
  const RbfFlow<D> flow(grid, w, {1.2, steps, segments});
  std::vector<RbfFlow<D>> parts;
  for (int g = 0; g < segments; ++g)
    parts.emplace_back(grid, w.middleRows(g * m, m), FlowSettings<D>{0.4, steps / segments, 1});
  FlowWorkspace<D> ws = flow.MakeWorkspace();
  std::mt19937_64 rng(seed);
  double moved = 0;
  for (int n = 0; n < 20; ++n) {
    const Vec<D> x = RandomPoint<D>(&rng, -0.5, 0.5);
    Mat<D> j;
    const Vec<D> z = flow.Forward(x, &ws, &j);
    Vec<D> composed = x;
    Mat<D> composed_j = Mat<D>::Identity();
    for (const RbfFlow<D>& part : parts) {
      Mat<D> jp;
      composed = part.Forward(composed, &ws, &jp);
      composed_j = jp * composed_j;
    }
    EXPECT_TRUE(testing::MatricesNear(z, composed, 1e-14)) << x.transpose();
    EXPECT_TRUE(testing::MatricesNear(j, composed_j, 1e-12 * (1 + j.norm()))) << x.transpose();
    moved = std::max(moved, (z - x).norm());
    Vec<D> back;
    ASSERT_TRUE(flow.Inverse(z, &ws, &back));
    EXPECT_LE((back - x).norm(), 1e-10) << x.transpose();
  }
  EXPECT_GT(moved, 0.05);
  // The segments differ: the same flow with segment 0's weights everywhere maps elsewhere.
  Eigen::MatrixXd first = w;
  for (int g = 1; g < segments; ++g) first.middleRows(g * m, m) = w.topRows(m);
  const RbfFlow<D> stationary(grid, first, {1.2, steps, segments});
  const Vec<D> x = Vec<D>::Constant(0.1);
  EXPECT_GT((stationary.Forward(x, &ws) - flow.Forward(x, &ws)).norm(), 1e-3);
}

TEST(RbfFlow, SegmentsAreACompositionOfFlows2D) { CheckSegmentsCompose(Grid2(), 0.08, 31); }
TEST(RbfFlow, SegmentsAreACompositionOfFlows3D) { CheckSegmentsCompose(Grid3(), 0.05, 32); }

// When S does not divide K, step k uses segment floor(k S / K): checked against a loop over the
// steps with each segment's own one-step flow, and the Jacobian against finite differences.
TEST(RbfFlow, UnevenSegmentsFollowTheStepRuleAndTheirJacobianIsExact) {
  const RbfGrid<2> grid(SmoothGrid<2>());
  const int segments = 3, steps = 7, m = grid.size();
  const Eigen::MatrixXd w = RandomWeights<2>(segments * m, 0.1, 33);
  const RbfFlow<2> flow(grid, w, {0.7, steps, segments});
  EXPECT_EQ(SegmentOfStep(flow.settings(), 0), 0);
  EXPECT_EQ(SegmentOfStep(flow.settings(), 2), 0);  // floor(6 / 7)
  EXPECT_EQ(SegmentOfStep(flow.settings(), 3), 1);  // floor(9 / 7)
  EXPECT_EQ(SegmentOfStep(flow.settings(), 6), 2);  // floor(18 / 7)
  FlowWorkspace<2> ws = flow.MakeWorkspace();
  std::mt19937_64 rng(33);
  for (int n = 0; n < 10; ++n) {
    const Vec<2> x = RandomPoint<2>(&rng, -0.15, 0.15);
    Vec<2> s = x;
    for (int k = 0; k < steps; ++k) {
      const int g = static_cast<int>(std::floor(k * 3.0 / 7.0));
      const RbfFlow<2> one(grid, w.middleRows(g * m, m), {0.1, 1});
      s = one.Forward(s, &ws);
    }
    Mat<2> j;
    EXPECT_TRUE(testing::MatricesNear(flow.Forward(x, &ws, &j), s, 1e-14));
    const Mat<2> j_fd =
        FiniteDifferenceJacobian<2>([&](const Vec<2>& p) { return flow.Forward(p, &ws); }, x);
    EXPECT_TRUE(testing::MatricesNear(j, j_fd, 1e-6 * (1 + j.norm())));
    EXPECT_GT((j - Mat<2>::Identity()).norm(), 0.02);  // a non-trivial map
    Vec<2> back;
    ASSERT_TRUE(flow.Inverse(flow.Forward(x, &ws), &ws, &back));
    EXPECT_LE((back - x).norm(), 1e-10);
  }
  Eigen::Matrix<double, 2, -1> points(2, 25);
  for (Eigen::Index i = 0; i < points.cols(); ++i) points.col(i) = RandomPoint<2>(&rng, -0.2, 0.2);
  const InvertibilityReport report = CheckInvertible<2>(flow, points, 1e-10);
  EXPECT_TRUE(report.ok) << report.Describe();
}

TEST(RbfFlow, BadSegmentsAreAnError) {
  const RbfGrid<2> grid(Grid2());
  testing::ExpectErrorContains(
      [&] {
        RbfFlow<2> f(grid, Eigen::MatrixXd::Zero(grid.size(), 2), {1.0, 10, 2}, "flow y");
      },
      {"flow y", "441 x 2", "882 x 2"});
  testing::ExpectErrorContains(
      [&] {
        RbfFlow<2> f(grid, Eigen::MatrixXd::Zero(11 * grid.size(), 2), {1.0, 10, 11});
      },
      {"segments 11", "steps = 10"});
  testing::ExpectErrorContains(
      [&] {
        RbfFlow<2> f(grid, Eigen::MatrixXd::Zero(grid.size(), 2), {1.0, 10, 0});
      },
      {"segments 0"});
}

// ---- imitation system --------------------------------------------------------------------------

// f_i by a dense, independent evaluation: brute-force features, Euler with the variational
// equation, an explicit inverse.
template <int D>
Vec<D> DenseVelocity(const RbfGridSpec<D>& g, const Eigen::MatrixXd& w, double time, int steps,
                     const Vec<D>& goal, double speed, const Vec<D>& x) {
  const double h = time / steps;
  auto flow = [&](const Vec<D>& start, Mat<D>* jac) {
    Vec<D> s = start;
    Mat<D> j = Mat<D>::Identity();
    for (int k = 0; k < steps; ++k) {
      const Eigen::VectorXd phi = BruteFeatures(g, s);
      Vec<D> v = w.transpose() * phi;
      Mat<D> dv = Mat<D>::Zero();
      for (int t = 0; t < phi.size(); ++t)
        if (phi[t] != 0)
          dv +=
              w.row(t).transpose() * (-2 * g.gamma * phi[t] * (s - BruteCentre(g, t))).transpose();
      j = (Mat<D>::Identity() + h * dv) * j;
      s += h * v;
    }
    *jac = j;
    return s;
  };
  Mat<D> j, unused;
  const Vec<D> z = flow(x, &j);
  const Vec<D> ze = flow(goal, &unused);
  return -speed * j.inverse() * (z - ze) / (z - ze).norm();
}

template <int D>
void CheckVelocity(const RbfGridSpec<D>& spec, double scale, std::uint64_t seed) {
  const RbfGrid<D> grid(spec);
  const Eigen::MatrixXd w = RandomWeights<D>(grid.size(), scale, seed);
  const Vec<D> goal = Vec<D>::Constant(0.05);
  const ImitationSystem<D> system(RbfFlow<D>(grid, w, {1.5, 12}), goal, 0.7);
  FlowWorkspace<D> ws = system.flow().MakeWorkspace();
  EXPECT_TRUE(testing::MatricesNear(system.goal_image(), system.flow().Forward(goal, &ws), 0));
  std::mt19937_64 rng(seed);
  for (int n = 0; n < 20; ++n) {
    const Vec<D> x = RandomPoint<D>(&rng, -0.6, 0.6);
    Vec<D> z;
    const Vec<D> v = system.Velocity(x, &ws, &z);
    const Vec<D> expected = DenseVelocity<D>(spec, w, 1.5, 12, goal, 0.7, x);
    EXPECT_TRUE(testing::MatricesNear(v, expected, 1e-10 * (1 + expected.norm())));
    EXPECT_TRUE(testing::MatricesNear(z, system.flow().Forward(x, &ws), 0));
  }
  EXPECT_TRUE(testing::MatricesNear(system.Velocity(goal, &ws), Vec<D>::Zero(), 0));
}

TEST(ImitationSystem, VelocityEqualsDenseEvaluation2D) { CheckVelocity(Grid2(), 0.1, 7); }
TEST(ImitationSystem, VelocityEqualsDenseEvaluation3D) { CheckVelocity(Grid3(), 0.05, 8); }

template <int D>
void CheckRolloutsReachGoal(const RbfGridSpec<D>& spec, double scale, std::uint64_t seed,
                            int starts) {
  const RbfGrid<D> grid(spec);
  const Vec<D> goal = Vec<D>::Constant(-0.1);
  const ImitationSystem<D> system(
      RbfFlow<D>(grid, RandomWeights<D>(grid.size(), scale, seed), {1.0, 10}), goal, 1.0);
  FlowWorkspace<D> ws = system.flow().MakeWorkspace();
  RolloutSettings settings;
  settings.dt = 0.005;
  settings.max_steps = 3000;
  settings.goal_tolerance = 0.02;
  std::mt19937_64 rng(seed);
  for (int i = 0; i < starts; ++i) {
    // Starts on a sphere of radius 0.6 around the goal.
    Vec<D> dir = RandomPoint<D>(&rng, -1, 1);
    if constexpr (D == 2)
      dir = Vec<D>(std::cos(2 * M_PI * i / starts), std::sin(2 * M_PI * i / starts));
    const Vec<D> start = goal + 0.6 * dir.normalized();
    const Rollout<D> r =
        RollOut<D>([&](const Vec<D>& x) { return system.Velocity(x, &ws); }, start, goal, settings);
    EXPECT_TRUE(r.reached) << "from " << start.transpose() << ", ended at "
                           << r.path.col(r.path.cols() - 1).transpose();
    EXPECT_TRUE(r.finite);
    EXPECT_TRUE(testing::MatricesNear(r.path.col(0), start, 0));
    // Lyapunov: ||psi(x) - z_e|| falls by about speed dt per Euler step (until it is about dt).
    double previous = (system.flow().Forward(start, &ws) - system.goal_image()).norm();
    for (Eigen::Index k = 1; k < r.path.cols() && previous > 2 * settings.dt; ++k) {
      const Vec<D> col = r.path.col(k);
      const double d = (system.flow().Forward(col, &ws) - system.goal_image()).norm();
      // speed dt to first order; the flow's curvature adds O(dt^2 ||J^-1||^2).
      EXPECT_GT(previous - d, 0.5 * settings.dt) << "step " << k;
      EXPECT_LT(previous - d, 2.0 * settings.dt) << "step " << k;
      previous = d;
    }
  }
}

TEST(ImitationSystem, RolloutsReachTheGoal2D) { CheckRolloutsReachGoal(Grid2(), 0.05, 11, 16); }
TEST(ImitationSystem, RolloutsReachTheGoal3D) { CheckRolloutsReachGoal(Grid3(), 0.03, 12, 8); }

TEST(RollOut, StopsOnNonFiniteVelocityAndChecksSettings) {
  RolloutSettings s;
  const Rollout<2> r = RollOut<2>(
      [](const Vec<2>& y) { return y[0] > 0.5 ? Vec<2>(std::nan(""), 0) : Vec<2>(1, 0); },
      Vec<2>(0, 0), Vec<2>(5, 0), s);
  EXPECT_FALSE(r.finite);
  EXPECT_FALSE(r.reached);
  EXPECT_NEAR(r.path(0, r.path.cols() - 1), 0.5, 0.011);
  s.dt = 0;
  testing::ExpectErrorContains(
      [&] {
        RollOut<2>([](const Vec<2>&) { return Vec<2>(1, 0); }, Vec<2>(0, 0), Vec<2>(1, 0), s);
      },
      {"dt"});
}

}  // namespace
}  // namespace foresight::imitation
