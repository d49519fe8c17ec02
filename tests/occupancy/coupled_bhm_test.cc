// The learning Fast-BHM (coupled weights, learned bound) against dense references: the full BHM,
// a dense batch EM, the ELBO by Gauss-Hermite quadrature, fusion of information, and its AUC.

#include "models/occupancy/coupled_bhm.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "core/binary_metrics.h"
#include "models/occupancy/bhm.h"
#include "models/occupancy/fast_bhm.h"
#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::occupancy {
namespace {

using testing::PointSet;

HingeGridConfig Small() { return testing::SmallGrid(4.0, 3.5, 6.71, 1.0); }  // 8 x 7 features

double RefLambda(double z) {
  return z == 0 ? 0.125 : (testing::ReferenceSigmoid(z) - 0.5) / (2 * z);
}

/// Dense batch variational EM in information form, written from the formulas.
struct DenseEm {
  Eigen::MatrixXd phi;  // [n x T]
  Eigen::VectorXd target, z;
  double m0, s0;
  Eigen::VectorXd mu;
  Eigen::MatrixXd sigma;

  DenseEm(const HingeGridConfig& c, const PointSet& p, double prior_mean, double prior_variance)
      : phi(testing::DenseDesign(c, p.xy)), m0(prior_mean), s0(prior_variance) {
    target.resize(p.xy.cols());
    for (Eigen::Index n = 0; n < target.size(); ++n) target[n] = p.occupied[n] ? 0.5 : -0.5;
    z = Eigen::VectorXd::Ones(target.size());
  }
  void EStep() {
    const int t = static_cast<int>(phi.cols());
    Eigen::VectorXd lambda(z.size());
    for (Eigen::Index n = 0; n < z.size(); ++n) lambda[n] = RefLambda(z[n]);
    const Eigen::MatrixXd p =
        Eigen::MatrixXd::Identity(t, t) / s0 + 2 * phi.transpose() * lambda.asDiagonal() * phi;
    const Eigen::LLT<Eigen::MatrixXd> llt(p);
    sigma = llt.solve(Eigen::MatrixXd::Identity(t, t));
    mu = llt.solve(Eigen::VectorXd::Constant(t, m0 / s0) + phi.transpose() * target);
  }
  void MStep() {
    for (Eigen::Index n = 0; n < z.size(); ++n) {
      const Eigen::VectorXd f = phi.row(n).transpose();
      z[n] = std::sqrt(f.dot(sigma * f) + std::pow(f.dot(mu), 2));
    }
  }
  /// KL(N(mu, Sigma) || N(m0, s0 I)) with a dense log-determinant.
  double Kl() const {
    const double t = static_cast<double>(mu.size());
    const Eigen::LLT<Eigen::MatrixXd> llt(sigma);
    const double log_det = 2 * llt.matrixLLT().diagonal().array().log().sum();
    return 0.5 * (sigma.trace() / s0 + (mu.array() - m0).square().sum() / s0 - t +
                  t * std::log(s0) - log_det);
  }
  /// Expected JJ log-bound of point n at bound zn under f ~ N(phi mu, phi' Sigma phi), by
  /// 20-node Gauss-Hermite quadrature (nodes from the Golub-Welsch eigenproblem).
  double ExpectedLogBound(Eigen::Index n, double zn) const {
    constexpr int kNodes = 20;
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(kNodes, kNodes);
    for (int k = 1; k < kNodes; ++k) j(k, k - 1) = j(k - 1, k) = std::sqrt(k / 2.0);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(j);
    const Eigen::VectorXd f = phi.row(n).transpose();
    const double m = f.dot(mu), v = f.dot(sigma * f);
    const double t = 2 * target[n];
    double e = 0;
    for (int k = 0; k < kNodes; ++k) {
      const double w = std::pow(eig.eigenvectors()(0, k), 2);  // weights / sqrt(pi)
      const double fx = m + std::sqrt(2 * v) * eig.eigenvalues()[k];
      e += w * (std::log(testing::ReferenceSigmoid(zn)) + (t * fx - zn) / 2 -
                RefLambda(zn) * (fx * fx - zn * zn));
    }
    return e;
  }
  double Elbo() const {
    double e = -Kl();
    for (Eigen::Index n = 0; n < z.size(); ++n) e += ExpectedLogBound(n, z[n]);
    return e;
  }
};

void ExpectRelNear(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double rel) {
  ASSERT_EQ(a.size(), b.size());
  for (Eigen::Index i = 0; i < a.size(); ++i)
    EXPECT_NEAR(a[i], b[i], rel * std::max(1.0, std::abs(b[i]))) << "entry " << i;
}

PointSet Scan(int n, std::uint64_t seed) {
  return testing::RandomPoints(n, 0.2, 3.8, 0.2, 3.3, seed);
}

TEST(CoupledBhm, FitZeroEqualsDenseBhmAtUnitBound) {
  const HingeGrid grid(Small());
  const PointSet a = Scan(120, 1), b = Scan(100, 2);
  FastBhmConfig dense_config;
  dense_config.prior_variance = 10;
  BhmLearner dense(grid, dense_config);
  dense.Update(a.xy, a.occupied.data());
  dense.Update(b.xy, b.occupied.data());
  CoupledBhmOptions options;
  options.prior_variance = 10;
  CoupledBhmLearner coupled(grid, options);
  coupled.Add(a.xy, a.occupied.data());
  coupled.Add(b.xy, b.occupied.data());
  const auto reports = coupled.Fit(0);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(coupled.points(), 220);
  ExpectRelNear(coupled.mean(), dense.mean(), 1e-8);
  ExpectRelNear(coupled.variance(), dense.covariance().diagonal(), 1e-8);
  const HingeMap map = coupled.ToMap();
  EXPECT_EQ(map.kind(), HingeMapKind::kFastBhm);
  ExpectRelNear(map.weights().variance, coupled.variance(), 0);
}

TEST(CoupledBhm, BoundUpdatesEqualDenseBatchEmAndElbo) {
  const HingeGrid grid(Small());
  const PointSet p = testing::Concat(Scan(150, 3), Scan(150, 4));
  CoupledBhmOptions options;
  options.prior_mean = 0.2;
  options.prior_variance = 5;
  CoupledBhmLearner coupled(grid, options);
  coupled.Add(p.xy, p.occupied.data());
  const auto reports = coupled.Fit(3);
  ASSERT_EQ(reports.size(), 4u);
  DenseEm ref(Small(), p, 0.2, 5);
  for (int u = 0; u <= 3; ++u) {
    if (u > 0) ref.MStep();
    ref.EStep();
    EXPECT_EQ(reports[u].update, u);
    const double elbo = ref.Elbo();  // quadrature, dense KL
    EXPECT_NEAR(reports[u].elbo, elbo, 1e-8 * std::abs(elbo)) << "update " << u;
    if (u > 0) {
      EXPECT_GE(reports[u].elbo, reports[u - 1].elbo - 1e-9 * std::abs(reports[u - 1].elbo));
      EXPECT_GT(reports[u].mean_abs_dz, 0);
    }
  }
  ExpectRelNear(coupled.mean(), ref.mu, 1e-8);
  ExpectRelNear(coupled.variance(), ref.sigma.diagonal(), 1e-8);
  EXPECT_DOUBLE_EQ(coupled.Elbo(), reports.back().elbo);
  for (int n = 0; n < coupled.points(); ++n) EXPECT_NEAR(coupled.bounds()[n], ref.z[n], 1e-8);
}

TEST(CoupledBhm, ElboNeverDecreasesAndMStepIsStationary) {
  const HingeGrid grid(Small());
  const PointSet p = Scan(250, 5);
  CoupledBhmLearner coupled(grid, CoupledBhmOptions{});
  coupled.Add(p.xy, p.occupied.data());
  const auto reports = coupled.Fit(5);
  ASSERT_EQ(reports.size(), 6u);
  for (int u = 1; u <= 5; ++u) EXPECT_GE(reports[u].elbo, reports[u - 1].elbo) << "update " << u;
  // At fixed posterior, z* = sqrt(phi' Sigma phi + (phi mu)^2) maximises each point's expected
  // log-bound: its derivative in z_n vanishes there (central differences).
  DenseEm ref(Small(), p, 0, 1e4);
  ref.EStep();
  ref.MStep();  // ref.z = the optimum for the posterior of the E-step at z = 1
  const double h = 1e-5;
  for (Eigen::Index n = 0; n < 20; ++n) {
    const double zs = ref.z[n];
    const double d = (ref.ExpectedLogBound(n, zs + h) - ref.ExpectedLogBound(n, zs - h)) / (2 * h);
    EXPECT_NEAR(d, 0.0, 1e-6) << "point " << n;
    // ... and it is a maximum: moving away lowers the bound.
    EXPECT_LT(ref.ExpectedLogBound(n, zs * 1.2), ref.ExpectedLogBound(n, zs));
  }
}

TEST(CoupledBhm, FusedInformationEqualsOneLearnerOnAllScans) {
  const HingeGrid grid(Small());
  const PointSet a = testing::RandomPoints(150, 0.2, 2.5, 0.2, 3.3, 6);
  const PointSet b = testing::RandomPoints(150, 1.5, 3.8, 0.2, 3.3, 7);
  CoupledBhmOptions options;
  options.prior_variance = 20;
  CoupledBhmLearner ra(grid, options), rb(grid, options), all(grid, options);
  ra.Add(a.xy, a.occupied.data());
  rb.Add(b.xy, b.occupied.data());
  all.Add(a.xy, a.occupied.data());
  all.Add(b.xy, b.occupied.data());
  ra.Fit(0);
  rb.Fit(0);
  all.Fit(0);
  const SparseInformation ia = ra.DataInformation(), ib = rb.DataInformation();
  EXPECT_GT(ia.Bytes(), 0u);
  EXPECT_EQ(ia.Bytes(),
            ia.precision_data.nonZeros() * 12 + (grid.size() + 1) * 4 + grid.size() * 8);
  const HingeMap fused = CoupledBhmLearner::FuseInformation(grid, options, {ia, ib});
  ExpectRelNear(fused.weights().mean, all.mean(), 1e-9);
  ExpectRelNear(fused.weights().variance, all.variance(), 1e-9);
  // No parts: the prior.
  const HingeMap prior = CoupledBhmLearner::FuseInformation(grid, options, {});
  EXPECT_NEAR(prior.weights().variance.maxCoeff(), 20, 1e-12);
}

/// A 8 m x 6 m room scanned from `poses` robot positions: 90 rays each, the wall hit occupied
/// (range noise +-0.1 m), free points every `step` m along the ray; a fraction `flip` of the labels
/// flipped.
PointSet RoomScans(int poses, double flip, std::uint64_t seed, double step) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(1.0, 7.0), uy(1.0, 5.0), noise(-0.1, 0.1);
  std::bernoulli_distribution flipped(flip);
  std::vector<double> xs, ys;
  std::vector<std::uint8_t> labels;
  for (int k = 0; k < poses; ++k) {
    const double x0 = ux(rng), y0 = uy(rng);
    for (int r = 0; r < 90; ++r) {
      const double a = 2 * M_PI * (r + 0.5) / 90, c = std::cos(a), s = std::sin(a);
      const double tx = c > 0 ? (8 - x0) / c : (c < 0 ? -x0 / c : 1e9);
      const double ty = s > 0 ? (6 - y0) / s : (s < 0 ? -y0 / s : 1e9);
      const double range = std::min(tx, ty);
      for (double d = step; d < range - step; d += step) {
        xs.push_back(x0 + d * c);
        ys.push_back(y0 + d * s);
        labels.push_back(flipped(rng) ? 1 : 0);
      }
      xs.push_back(x0 + range * c + noise(rng));
      ys.push_back(y0 + range * s + noise(rng));
      labels.push_back(flipped(rng) ? 0 : 1);
    }
  }
  PointSet p;
  p.xy.resize(2, static_cast<Eigen::Index>(xs.size()));
  for (std::size_t i = 0; i < xs.size(); ++i)
    p.xy.col(static_cast<Eigen::Index>(i)) << xs[i], ys[i];
  p.occupied = labels;
  return p;
}

double Auc(const HingeMap& map, const PointSet& test) {
  MapWorkspace ws = map.MakeWorkspace();
  std::vector<double> scores(test.occupied.size());
  for (std::size_t i = 0; i < scores.size(); ++i)
    scores[i] = map.Probability(test.xy(0, i), test.xy(1, i), &ws);
  return EvaluateBinary(scores, test.occupied).auc;
}

TEST(CoupledBhm, LearnedBoundBeatsPublishedFastBhmOnNoisyRoom) {
  HingeGridConfig c;
  c.x_min = -1;
  c.x_max = 9;
  c.y_min = -1;
  c.y_max = 7;
  c.spacing = 0.5;
  c.gamma = 6.71;
  c.cutoff_radius = 1.0;
  const HingeGrid grid(c);
  // Dense free points (every 0.1 m): the published update lets every overlapping feature count
  // them again and washes out the walls. Training labels 5 % flipped, test labels clean.
  const PointSet train = RoomScans(2, 0.05, 11, 0.1), test = RoomScans(3, 0.0, 12, 0.1);
  CoupledBhmLearner coupled(grid, CoupledBhmOptions{});
  FastBhmLearner fast(grid, FastBhmConfig{});
  coupled.Add(train.xy, train.occupied.data());
  fast.Update(train.xy, train.occupied.data());
  coupled.Fit(5);
  const double auc_coupled = Auc(coupled.ToMap(), test), auc_fast = Auc(fast.ToMap(), test);
  EXPECT_GT(auc_coupled, auc_fast) << "coupled " << auc_coupled << " published " << auc_fast;
}

TEST(CoupledBhm, BadInputIsAnErrorNamingIt) {
  const HingeGrid grid(Small());
  CoupledBhmLearner learner(grid, CoupledBhmOptions{});
  testing::ExpectErrorContains([&] { learner.Fit(0); }, {"call Add() first"});
  PointSet p = Scan(10, 8);
  learner.Add(p.xy, p.occupied.data());
  testing::ExpectErrorContains([&] { learner.DataInformation(); }, {"Fit()"});
  testing::ExpectErrorContains([&] { learner.Elbo(); }, {"Fit()"});
  testing::ExpectErrorContains([&] { learner.Fit(-1); }, {"bound_updates = -1"});
  p.xy(1, 4) = std::nan("");
  testing::ExpectErrorContains([&] { learner.Add(p.xy, p.occupied.data()); },
                               {"scan 1", "point 4", "non-finite", "nan"});
  learner.Fit(0);
  SparseInformation info = learner.DataInformation();
  const HingeGrid other(testing::SmallGrid(3.0, 3.5, 6.71, 1.0));
  testing::ExpectErrorContains(
      [&] { CoupledBhmLearner::FuseInformation(other, CoupledBhmOptions{}, {info}); },
      {"part 0", "56 features", "42"});
  CoupledBhmOptions bad;
  bad.prior_variance = -1;
  testing::ExpectErrorContains([&] { CoupledBhmLearner(grid, bad); }, {"prior_variance = -1"});
}

}  // namespace
}  // namespace foresight::occupancy
