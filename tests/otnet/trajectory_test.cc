// OTNet's trajectory basis and metrics (thesis ch 6, "Learning a Mixture of Stochastic Processes",
// "Dataset and Metrics"). Basis: the ridge fit recovers weights of a trajectory in the span, smooth
// curves of any length are reproduced, the design matrix is the Gaussian RBF written out here.
// Metrics: resampling, Hausdorff and Frechet distances on cases with known answers, the mean
// minimum distance, the ANLL against the 2 x 2 Gaussian density written with Eigen's inverse and
// determinant (and stable far away), the per-time Gaussian fit against sample moments; errors.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <random>

#include "inference/otnet/trajectory_basis.h"
#include "inference/otnet/trajectory_metrics.h"
#include "tests/test_util.h"

namespace foresight::otnet {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::MatricesNear;

constexpr double kPi = 3.14159265358979323846;

Eigen::VectorXd RandomVector(int n, std::uint64_t seed, double scale) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::VectorXd v(n);
  for (auto& x : v) x = scale * n01(rng);
  return v;
}

// ---------------------------------------------------------------- basis

TEST(UniformTaus, AreIOverCountMinusOne) {
  Eigen::VectorXd expected(5);
  expected << 0.0, 0.25, 0.5, 0.75, 1.0;
  EXPECT_TRUE(MatricesNear(UniformTaus(5), expected, 0.0));
  const Eigen::VectorXd t = UniformTaus(7);
  for (int i = 0; i < 7; ++i) EXPECT_DOUBLE_EQ(t[i], i / 6.0);
  EXPECT_EQ(UniformTaus(2)[1], 1.0);
  ExpectErrorContains([] { UniformTaus(1); }, {"UniformTaus", "got 1"});
}

TEST(TrajectoryBasis, DesignIsTheGaussianRbfAtEvenlySpacedCentres) {
  const int m = 6;
  const double gamma = 30;
  const TrajectoryBasis basis(m, gamma, 1e-3);
  EXPECT_EQ(basis.size(), m);
  EXPECT_EQ(basis.weights(), 2 * m);
  EXPECT_EQ(basis.gamma(), gamma);
  EXPECT_EQ(basis.ridge(), 1e-3);
  Eigen::VectorXd taus(4);
  taus << 0.0, 0.13, 0.5, 1.0;
  const Eigen::MatrixXd k = basis.Design(taus);
  ASSERT_EQ(k.rows(), 4);
  ASSERT_EQ(k.cols(), m);
  for (int l = 0; l < 4; ++l)
    for (int j = 0; j < m; ++j) {
      const double c = static_cast<double>(j) / (m - 1);
      EXPECT_NEAR(k(l, j), std::exp(-gamma * (taus[l] - c) * (taus[l] - c)), 1e-15);
    }
  EXPECT_TRUE(MatricesNear(k, TimeBasis(m, 0.0, 1.0, gamma).Design(taus), 0.0));
}

TEST(TrajectoryBasis, EvaluateIsTheWeightedSumOfBasisFunctions) {
  const TrajectoryBasis basis(5, 12, 0);
  const Eigen::VectorXd w = RandomVector(10, 1, 3.0);
  const Eigen::VectorXd taus = UniformTaus(9);
  const Eigen::MatrixX2d xy = basis.Evaluate(w, taus);
  for (int l = 0; l < 9; ++l) {
    double x = 0, y = 0;
    for (int j = 0; j < 5; ++j) {
      const double k = std::exp(-12 * std::pow(taus[l] - j / 4.0, 2));
      x += w[j] * k;
      y += w[5 + j] * k;
    }
    EXPECT_NEAR(xy(l, 0), x, 1e-12);
    EXPECT_NEAR(xy(l, 1), y, 1e-12);
  }
}

TEST(TrajectoryBasis, FitRecoversTheWeightsOfATrajectoryInTheSpan) {
  const TrajectoryBasis basis(8, 20, 0.0);
  for (int n : {12, 30, 57}) {
    const Eigen::VectorXd w = RandomVector(16, static_cast<std::uint64_t>(n), 5.0);
    // Waypoints at tau_i = i / (n - 1), written out here rather than with UniformTaus.
    Eigen::VectorXd taus(n);
    for (int i = 0; i < n; ++i) taus[i] = static_cast<double>(i) / (n - 1);
    const Eigen::MatrixX2d waypoints = basis.Evaluate(w, taus);
    const Eigen::VectorXd fitted = basis.Fit(waypoints);
    EXPECT_TRUE(MatricesNear(fitted, w, 1e-6)) << n << " waypoints";
  }
}

TEST(TrajectoryBasis, ReproducesSmoothCurvesOfDifferentLengths) {
  // A curve in Occ-Traj120's range (cells). The Gaussian RBFs have no constant term, so the offset
  // of ~20 cells costs a little near the ends: measured max 0.05 cells at n = 24, 0.03 at n = 58.
  const TrajectoryBasis basis(16, 30, 1e-8);
  auto curve = [](double t) {
    return Eigen::RowVector2d(20 + 10 * std::cos(kPi * t), 5 * std::sin(2 * kPi * t) + 12 * t);
  };
  for (int n : {5, 8, 24, 58}) {
    Eigen::MatrixX2d waypoints(n, 2);
    for (int i = 0; i < n; ++i) waypoints.row(i) = curve(static_cast<double>(i) / (n - 1));
    const Eigen::VectorXd w = basis.Fit(waypoints);
    ASSERT_EQ(w.size(), 32);
    const Eigen::MatrixX2d at_waypoints = basis.Evaluate(w, UniformTaus(n));
    // Fewer waypoints than basis functions: the fit interpolates them (up to the tiny ridge).
    const double tol = n < basis.size() ? 1e-5 : 0.08;
    EXPECT_LT((at_waypoints - waypoints).rowwise().norm().maxCoeff(), tol) << n << " waypoints";
    if (n >= 24) {  // enough samples to pin the curve between them too
      const Eigen::VectorXd dense = UniformTaus(201);
      const Eigen::MatrixX2d xy = basis.Evaluate(w, dense);
      for (int l = 0; l < 201; ++l)
        EXPECT_LT((xy.row(l) - curve(dense[l])).norm(), 0.08)
            << n << " waypoints, tau " << dense[l];
    }
  }
}

TEST(TrajectoryBasis, Errors) {
  ExpectErrorContains([] { TrajectoryBasis(1, 10, 0); }, {"num_basis", "got 1"});
  ExpectErrorContains([] { TrajectoryBasis(4, 0, 0); }, {"gamma", "got 0"});
  ExpectErrorContains([] { TrajectoryBasis(4, -3, 0); }, {"gamma", "got -3"});
  ExpectErrorContains([] { TrajectoryBasis(4, std::nan(""), 0); }, {"gamma", "nan"});
  ExpectErrorContains([] { TrajectoryBasis(4, 10, -1e-3); }, {"ridge", "got -0.001"});
  const TrajectoryBasis basis(4, 10, 1e-4);
  ExpectErrorContains([&] { basis.Fit(Eigen::MatrixX2d(1, 2)); },
                      {"Fit", "at least 2 waypoints", "got 1"});
  ExpectErrorContains([&] { basis.Fit(Eigen::MatrixX2d(0, 2)); }, {"Fit", "got 0"});
  Eigen::MatrixX2d bad = Eigen::MatrixX2d::Zero(5, 2);
  bad(3, 1) = std::numeric_limits<double>::infinity();
  ExpectErrorContains([&] { basis.Fit(bad); }, {"Fit", "waypoint 3", "not finite"});
  ExpectErrorContains([&] { basis.Evaluate(Eigen::VectorXd::Zero(7), UniformTaus(3)); },
                      {"Evaluate", "7 entries", "2M = 8"});
  ExpectErrorContains([] { TrajectoryBasis().Fit(Eigen::MatrixX2d::Zero(3, 2)); },
                      {"not initialised"});
}

// ---------------------------------------------------------------- metrics

Eigen::MatrixX2d Points(std::initializer_list<std::pair<double, double>> pts) {
  Eigen::MatrixX2d m(static_cast<Eigen::Index>(pts.size()), 2);
  Eigen::Index i = 0;
  for (const auto& [x, y] : pts) m.row(i++) << x, y;
  return m;
}

/// A horizontal segment from (x0, y) to (x1, y) with n points.
Eigen::MatrixX2d Segment(double x0, double x1, double y, int n) {
  Eigen::MatrixX2d m(n, 2);
  for (int i = 0; i < n; ++i) m.row(i) << x0 + (x1 - x0) * i / (n - 1), y;
  return m;
}

TEST(ResampleUniform, InterpolatesLinearlyInNormalisedTime) {
  // Waypoints at tau 0, 0.5, 1; samples at 0, 0.25, 0.5, 0.75, 1.
  const Eigen::MatrixX2d r = ResampleUniform(Points({{0, 0}, {1, 2}, {3, 2}}), 5);
  EXPECT_TRUE(MatricesNear(r, Points({{0, 0}, {0.5, 1}, {1, 2}, {2, 2}, {3, 2}}), 1e-15));
  // Uniform in time, not arc length: a long second step still gets half of the samples.
  const Eigen::MatrixX2d s = ResampleUniform(Points({{0, 0}, {1, 0}, {11, 0}}), 3);
  EXPECT_TRUE(MatricesNear(s, Points({{0, 0}, {1, 0}, {11, 0}}), 1e-15));
  // Endpoints exactly, count = 2.
  const Eigen::MatrixX2d w = Points({{0.3, 7.1}, {2, 2}, {5, 1}, {9.7, 3.3}});
  const Eigen::MatrixX2d e = ResampleUniform(w, 2);
  EXPECT_EQ(e.row(0), w.row(0));
  EXPECT_EQ(e.row(1), w.row(3));
  const Eigen::MatrixX2d many = ResampleUniform(w, 100);
  EXPECT_EQ(many.row(0), w.row(0));
  EXPECT_EQ(many.row(99), w.row(3));
  // Sample k at tau = k / 99 lies at s = 3k / 99 along the waypoint index: k = 33 is waypoint 1.
  EXPECT_NEAR((many.row(33) - w.row(1)).norm(), 0.0, 1e-12);
  // A single waypoint is repeated.
  const Eigen::MatrixX2d single = ResampleUniform(Points({{4, 5}}), 3);
  EXPECT_TRUE(MatricesNear(single, Points({{4, 5}, {4, 5}, {4, 5}}), 0.0));
}

TEST(ResampleUniform, Errors) {
  ExpectErrorContains([] { ResampleUniform(Points({{0, 0}, {1, 1}}), 1); }, {"count", "got 1"});
  ExpectErrorContains([] { ResampleUniform(Eigen::MatrixX2d(0, 2), 5); }, {"no waypoints"});
  ExpectErrorContains(
      [] {
        ResampleUniform(Points({{0, 0}, {std::nan(""), 1}}), 5);
      },
      {"waypoint 1", "not finite"});
}

TEST(TrajectoryDistances, KnownAnswers) {
  // Parallel segments 3 apart: both distances are 3.
  const Eigen::MatrixX2d a = Segment(0, 10, 0, 11), b = Segment(0, 10, 3, 11);
  EXPECT_NEAR(TrajectoryHausdorff(a, b), 3.0, 1e-12);
  EXPECT_NEAR(TrajectoryFrechet(a, b), 3.0, 1e-12);
  // The same segment walked backwards: the point sets coincide (Hausdorff 0) but the walks must
  // start at opposite ends (Frechet = the length, 10).
  const Eigen::MatrixX2d reversed = a.colwise().reverse();
  EXPECT_NEAR(TrajectoryHausdorff(a, reversed), 0.0, 1e-12);
  EXPECT_NEAR(TrajectoryFrechet(a, reversed), 10.0, 1e-12);
  // Asymmetric point sets: h(a, b) = 1, h(b, a) = 5, Hausdorff is the max.
  const Eigen::MatrixX2d p = Points({{0, 0}}), q = Points({{3, 4}, {0, 1}});
  EXPECT_NEAR(TrajectoryHausdorff(p, q), 5.0, 1e-12);
  EXPECT_NEAR(TrajectoryHausdorff(q, p), 5.0, 1e-12);
  EXPECT_NEAR(TrajectoryFrechet(p, q), 5.0, 1e-12);
  ExpectErrorContains([&] { TrajectoryHausdorff(Eigen::MatrixX2d(0, 2), p); },
                      {"TrajectoryHausdorff", "a has no points"});
  ExpectErrorContains([&] { TrajectoryFrechet(p, Eigen::MatrixX2d(0, 2)); },
                      {"TrajectoryFrechet", "b has no points"});
}

TEST(MeanMinimumDistance, AveragesTheNearestGroundTruthDistance) {
  const std::vector<Eigen::MatrixX2d> generated = {Segment(0, 10, 0, 11), Segment(0, 10, 10, 11)};
  const std::vector<Eigen::MatrixX2d> truth = {Segment(0, 10, 1, 11), Segment(0, 10, 7, 11)};
  // Nearest: 1 (for y = 0) and 3 (for y = 10).
  EXPECT_NEAR(MeanMinimumDistance(generated, truth, TrajectoryDistance::kHausdorff), 2.0, 1e-12);
  EXPECT_NEAR(MeanMinimumDistance(generated, truth, TrajectoryDistance::kFrechet), 2.0, 1e-12);
  // Coverage (the reverse): y = 1 -> 1, y = 7 -> 3.
  EXPECT_NEAR(MeanMinimumDistance(truth, generated, TrajectoryDistance::kHausdorff), 2.0, 1e-12);
  // The reversed copy is 0 away by Hausdorff but 10 by Frechet.
  const std::vector<Eigen::MatrixX2d> back = {Segment(10, 0, 0, 11)};
  EXPECT_NEAR(MeanMinimumDistance(back, {Segment(0, 10, 0, 11)}, TrajectoryDistance::kHausdorff),
              0.0, 1e-12);
  EXPECT_NEAR(MeanMinimumDistance(back, {Segment(0, 10, 0, 11)}, TrajectoryDistance::kFrechet),
              10.0, 1e-12);
  ExpectErrorContains([&] { MeanMinimumDistance({}, truth, TrajectoryDistance::kFrechet); },
                      {"no generated"});
  ExpectErrorContains([&] { MeanMinimumDistance(generated, {}, TrajectoryDistance::kFrechet); },
                      {"no ground-truth"});
}

/// log N(x; mu, S) with Eigen's 2 x 2 inverse and determinant.
double LogNormal2(const Eigen::Vector2d& x, const Eigen::Vector2d& mu, const Eigen::Matrix2d& s) {
  const Eigen::Vector2d d = x - mu;
  return -std::log(2 * kPi) - 0.5 * std::log(s.determinant()) - 0.5 * d.dot(s.inverse() * d);
}

Eigen::Matrix2d Cov(const Eigen::MatrixXd& covs, int l) {
  Eigen::Matrix2d s;
  s << covs(l, 0), covs(l, 1), covs(l, 1), covs(l, 2);
  return s;
}

PerTimeDensity TwoComponents() {
  PerTimeDensity d;
  d.weights = Eigen::Vector2d(0.3, 0.7);
  d.means = {Points({{0, 0}, {1, 1}, {2, 1}}), Points({{0.5, -1}, {3, 0}, {2, 4}})};
  Eigen::MatrixXd c0(3, 3), c1(3, 3);
  c0 << 1.0, 0.3, 2.0, 0.5, -0.2, 0.4, 2.0, 0.0, 1.0;
  c1 << 0.7, 0.0, 0.7, 3.0, 1.5, 1.0, 0.2, -0.1, 0.9;
  d.covs = {c0, c1};
  return d;
}

TEST(AverageNegativeLogLikelihood, OneComponentClosedForm) {
  // At the mean of a standard normal: -log N = log(2 pi).
  PerTimeDensity unit;
  unit.weights = Eigen::VectorXd::Ones(1);
  unit.means = {Points({{1, 2}, {3, 4}})};
  unit.covs = {(Eigen::MatrixXd(2, 3) << 1, 0, 1, 1, 0, 1).finished()};
  EXPECT_NEAR(AverageNegativeLogLikelihood(unit, Points({{1, 2}, {3, 4}})), std::log(2 * kPi),
              1e-12);
  // One unit away in x at both times: + 1/2.
  EXPECT_NEAR(AverageNegativeLogLikelihood(unit, Points({{2, 2}, {3, 5}})), std::log(2 * kPi) + 0.5,
              1e-12);

  PerTimeDensity one = TwoComponents();
  one.weights = Eigen::VectorXd::Ones(1);
  one.means.pop_back();
  one.covs.pop_back();
  const Eigen::MatrixX2d truth = Points({{0.4, -0.3}, {2, 0.5}, {1, 2.5}});
  double expected = 0;
  for (int l = 0; l < 3; ++l)
    expected -=
        LogNormal2(truth.row(l).transpose(), one.means[0].row(l).transpose(), Cov(one.covs[0], l));
  EXPECT_NEAR(AverageNegativeLogLikelihood(one, truth), expected / 3, 1e-12);
}

TEST(AverageNegativeLogLikelihood, TwoComponentsClosedForm) {
  const PerTimeDensity d = TwoComponents();
  const Eigen::MatrixX2d truth = Points({{0.4, -0.3}, {2, 0.5}, {1, 2.5}});
  double expected = 0;
  for (int l = 0; l < 3; ++l) {
    double p = 0;  // the density itself, summed directly (no log-sum-exp)
    for (int q = 0; q < 2; ++q)
      p += d.weights[q] * std::exp(LogNormal2(truth.row(l).transpose(),
                                              d.means[q].row(l).transpose(), Cov(d.covs[q], l)));
    expected -= std::log(p);
  }
  EXPECT_NEAR(AverageNegativeLogLikelihood(d, truth), expected / 3, 1e-12);
}

TEST(AverageNegativeLogLikelihood, StaysFiniteFarFromEveryComponent) {
  // 1000 cells from unit-variance components: each density underflows to 0 in double, the
  // log-sum-exp keeps the answer finite and equal to the dominant term plus log1p of the other.
  PerTimeDensity d;
  d.weights = Eigen::Vector2d(0.5, 0.5);
  d.means = {Points({{0, 0}}), Points({{1, 0}})};
  d.covs = {(Eigen::MatrixXd(1, 3) << 1, 0, 1).finished(),
            (Eigen::MatrixXd(1, 3) << 1, 0, 1).finished()};
  const Eigen::MatrixX2d truth = Points({{1000, 0}});
  ASSERT_EQ(std::exp(-0.5 * 999.0 * 999.0), 0.0);
  const double l0 = std::log(0.5) - std::log(2 * kPi) - 0.5 * 1000.0 * 1000.0;
  const double l1 = std::log(0.5) - std::log(2 * kPi) - 0.5 * 999.0 * 999.0;
  const double expected = -(l1 + std::log1p(std::exp(l0 - l1)));
  const double anll = AverageNegativeLogLikelihood(d, truth);
  EXPECT_TRUE(std::isfinite(anll));
  EXPECT_NEAR(anll, expected, 1e-9 * expected);
  // A zero-weight component adds nothing.
  d.weights = Eigen::Vector2d(0.0, 1.0);
  EXPECT_NEAR(AverageNegativeLogLikelihood(d, truth), std::log(2 * kPi) + 0.5 * 999.0 * 999.0,
              1e-6);
}

TEST(AverageNegativeLogLikelihood, Errors) {
  const PerTimeDensity good = TwoComponents();
  ExpectErrorContains(
      [&] {
        AverageNegativeLogLikelihood(good, Points({{0, 0}, {1, 1}}));
      },
      {"truth has 2 points", "3 times"});
  PerTimeDensity bad = good;
  bad.covs[1](2, 1) = 1.0;  // cov_xy^2 > var_x var_y at time 2
  ExpectErrorContains(
      [&] {
        AverageNegativeLogLikelihood(bad, Points({{0, 0}, {1, 1}, {2, 2}}));
      },
      {"component 1", "time 2", "not positive definite"});
  bad = good;
  bad.covs[0](1, 0) = 0.0;
  ExpectErrorContains(
      [&] {
        AverageNegativeLogLikelihood(bad, Points({{0, 0}, {1, 1}, {2, 2}}));
      },
      {"component 0", "time 1", "not positive definite"});
  bad = good;
  bad.weights = Eigen::Vector2d(0.5, 0.7);
  ExpectErrorContains(
      [&] {
        AverageNegativeLogLikelihood(bad, Points({{0, 0}, {1, 1}, {2, 2}}));
      },
      {"weights sum to 1.2"});
  bad = good;
  bad.means.pop_back();
  ExpectErrorContains(
      [&] {
        AverageNegativeLogLikelihood(bad, Points({{0, 0}, {1, 1}, {2, 2}}));
      },
      {"2 weights but 1 means"});
  bad = good;
  bad.covs[1] = Eigen::MatrixXd::Ones(3, 2);
  ExpectErrorContains(
      [&] {
        AverageNegativeLogLikelihood(bad, Points({{0, 0}, {1, 1}, {2, 2}}));
      },
      {"covariances of component 1", "3 x 2"});
}

TEST(FitPerTimeGaussian, IsTheSampleMeanAndBiasedCovariancePlusTheFloor) {
  std::mt19937_64 rng(21);
  std::normal_distribution<double> n01;
  const int count = 6, times = 5;
  std::vector<Eigen::MatrixX2d> trajectories(count, Eigen::MatrixX2d(times, 2));
  for (auto& t : trajectories)
    for (Eigen::Index i = 0; i < t.size(); ++i) t.data()[i] = 3.0 * n01(rng);
  const double floor = 0.05;
  const PerTimeDensity d = FitPerTimeGaussian(trajectories, floor);
  ASSERT_EQ(d.weights.size(), 1);
  EXPECT_EQ(d.weights[0], 1.0);
  ASSERT_EQ(d.times(), times);
  for (int l = 0; l < times; ++l) {
    Eigen::MatrixXd x(count, 2);  // the samples at time l, one per row
    for (int k = 0; k < count; ++k) x.row(k) = trajectories[k].row(l);
    const Eigen::RowVector2d mean = x.colwise().mean();
    const Eigen::MatrixXd centred = x.rowwise() - mean;
    const Eigen::Matrix2d cov =
        centred.transpose() * centred / count + floor * Eigen::Matrix2d::Identity();
    EXPECT_NEAR((d.means[0].row(l) - mean).norm(), 0.0, 1e-12);
    EXPECT_NEAR(d.covs[0](l, 0), cov(0, 0), 1e-12);
    EXPECT_NEAR(d.covs[0](l, 1), cov(0, 1), 1e-12);
    EXPECT_NEAR(d.covs[0](l, 2), cov(1, 1), 1e-12);
  }
  // One trajectory: zero sample covariance, the floor alone keeps it definite.
  const PerTimeDensity single = FitPerTimeGaussian({trajectories[0]}, floor);
  EXPECT_NEAR(AverageNegativeLogLikelihood(single, trajectories[0]),
              std::log(2 * kPi) + std::log(floor), 1e-12);
}

TEST(FitPerTimeGaussian, Errors) {
  ExpectErrorContains([] { FitPerTimeGaussian({}, 0.1); }, {"no trajectories"});
  const Eigen::MatrixX2d a = Segment(0, 1, 0, 4);
  ExpectErrorContains([&] { FitPerTimeGaussian({a}, 0.0); }, {"variance_floor", "got 0"});
  ExpectErrorContains(
      [&] {
        FitPerTimeGaussian({a, Segment(0, 1, 0, 5)}, 0.1);
      },
      {"trajectory 1", "5 points", "4"});
  Eigen::MatrixX2d bad = a;
  bad(2, 0) = std::nan("");
  ExpectErrorContains(
      [&] {
        FitPerTimeGaussian({a, a, bad}, 0.1);
      },
      {"trajectory 2", "not finite"});
}

}  // namespace
}  // namespace foresight::otnet
