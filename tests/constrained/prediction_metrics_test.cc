// The metrics of thesis ch 7 (ADE, FDE of the nearest component and of the mixture mean, AL,
// ANLL), constant velocity and percentiles, against hand computations: positions from the basis
// written out here, densities from the closed-form 2-D Gaussian.

#include "inference/constrained/prediction_metrics.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "tests/test_util.h"

namespace foresight::constrained {
namespace {

using foresight::testing::ExpectErrorContains;

constexpr double kDt = 0.4;
constexpr int kSteps = 6;

TimeBasis Basis() { return TimeBasis(5, 0.0, 2.4, 1.5); }

/// Component r's mean and covariance at time t, written out from the model:
/// mu = origin + v t + M' phi, Sigma = (phi' L_U L_U' phi) L_V L_V'.
void HandPosition(const TrajectoryDistribution& d, int r, double t, Eigen::Vector2d* mu,
                  Eigen::Matrix2d* cov) {
  const TimeBasis basis = Basis();
  Eigen::VectorXd phi(basis.size());
  for (int j = 0; j < basis.size(); ++j) {
    const double dt = t - basis.centres()[j];
    phi[j] = std::exp(-basis.gamma() * dt * dt);
  }
  *mu = d.origin() + t * d.velocity() + d.mean(r).transpose() * phi;
  const Eigen::MatrixXd u = d.chol_u(r) * d.chol_u(r).transpose();
  *cov = phi.dot(u * phi) * d.chol_v(r) * d.chol_v(r).transpose();
}

double Gaussian2(const Eigen::Vector2d& x, const Eigen::Vector2d& mu, const Eigen::Matrix2d& cov) {
  const Eigen::Vector2d e = x - mu;
  return std::exp(-0.5 * e.dot(cov.inverse() * e)) / (2 * M_PI * std::sqrt(cov.determinant()));
}

TrajectoryDistribution Distribution(int components) {
  const TimeBasis basis = Basis();
  const int m = basis.size();
  TrajectoryDistribution d(basis, components);
  Eigen::VectorXd alpha = Eigen::VectorXd::LinSpaced(components, 1.0, 2.0);
  alpha /= alpha.sum();
  d.SetFrame(Eigen::Vector2d(1.0, -2.0), Eigen::Vector2d(0.8, 0.3), alpha);
  for (int r = 0; r < components; ++r) {
    Eigen::MatrixXd mean(m, 2);
    for (int j = 0; j < m; ++j) mean.row(j) << 0.1 * j * (r + 1), -0.2 * j * r + 0.05 * r;
    // A full (non-diagonal) L_U: the metrics do not need a diagonal U.
    Eigen::MatrixXd lu = Eigen::MatrixXd::Zero(m, m);
    for (int i = 0; i < m; ++i) {
      lu(i, i) = 0.3 + 0.05 * i + 0.1 * r;
      if (i > 0) lu(i, i - 1) = 0.05;
    }
    Eigen::Matrix2d lv;
    lv << 0.7 + 0.1 * r, 0, 0.2, 0.5;
    d.SetComponent(r, mean, lu, lv);
  }
  return d;
}

TEST(ScorePrediction, OneComponentMatchesTheClosedFormGaussian) {
  const TrajectoryDistribution d = Distribution(1);
  Eigen::MatrixX2d truth(kSteps, 2);
  for (int i = 0; i < kSteps; ++i) {
    Eigen::Vector2d mu;
    Eigen::Matrix2d cov;
    HandPosition(d, 0, (i + 1) * kDt, &mu, &cov);
    truth.row(i) = (mu + Eigen::Vector2d(0.1 * i, -0.05 * i * i)).transpose();
  }
  double ade = 0, fde = 0, al = 0, anll = 0;
  for (int i = 0; i < kSteps; ++i) {
    Eigen::Vector2d mu;
    Eigen::Matrix2d cov;
    HandPosition(d, 0, (i + 1) * kDt, &mu, &cov);
    const double e = (truth.row(i).transpose() - mu).norm();
    ade += e / kSteps;
    fde = e;
    const double p = Gaussian2(truth.row(i).transpose(), mu, cov);
    al += p / kSteps;
    anll -= std::log(p) / kSteps;
  }
  const PredictionScores s = ScorePrediction(d, truth, kDt);
  EXPECT_NEAR(s.ade_nearest, ade, 1e-12);
  EXPECT_NEAR(s.fde_nearest, fde, 1e-12);
  EXPECT_NEAR(s.ade_mixture, ade, 1e-12);
  EXPECT_NEAR(s.fde_mixture, fde, 1e-12);
  EXPECT_NEAR(s.al, al, 1e-10 * al);
  EXPECT_NEAR(s.anll, anll, 1e-10);
  EXPECT_EQ(s.nearest, 0);
  ASSERT_GT(ade, 0.05);
}

TEST(ScorePrediction, NearestComponentMixtureMeanAndMixtureDensity) {
  const TrajectoryDistribution d = Distribution(3);
  // The truth follows component 2's mean, perturbed.
  Eigen::MatrixX2d truth(kSteps, 2);
  for (int i = 0; i < kSteps; ++i) {
    Eigen::Vector2d mu;
    Eigen::Matrix2d cov;
    HandPosition(d, 2, (i + 1) * kDt, &mu, &cov);
    truth.row(i) = (mu + Eigen::Vector2d(0.02 * i, 0.03)).transpose();
  }
  std::vector<double> ade(3, 0.0), fde(3, 0.0);
  double ade_mix = 0, fde_mix = 0, al = 0, anll = 0;
  for (int i = 0; i < kSteps; ++i) {
    const Eigen::Vector2d x = truth.row(i).transpose();
    Eigen::Vector2d mix = Eigen::Vector2d::Zero();
    double p = 0;
    for (int r = 0; r < 3; ++r) {
      Eigen::Vector2d mu;
      Eigen::Matrix2d cov;
      HandPosition(d, r, (i + 1) * kDt, &mu, &cov);
      ade[r] += (x - mu).norm() / kSteps;
      fde[r] = (x - mu).norm();
      mix += d.alpha(r) * mu;
      p += d.alpha(r) * Gaussian2(x, mu, cov);
    }
    ade_mix += (x - mix).norm() / kSteps;
    fde_mix = (x - mix).norm();
    al += p / kSteps;
    anll -= std::log(p) / kSteps;
  }
  ASSERT_LT(ade[2], ade[0]);
  ASSERT_LT(ade[2], ade[1]);
  const PredictionScores s = ScorePrediction(d, truth, kDt);
  EXPECT_EQ(s.nearest, 2);
  EXPECT_NEAR(s.ade_nearest, ade[2], 1e-12);
  EXPECT_NEAR(s.fde_nearest, fde[2], 1e-12);
  EXPECT_NEAR(s.ade_mixture, ade_mix, 1e-12);
  EXPECT_NEAR(s.fde_mixture, fde_mix, 1e-12);
  EXPECT_NEAR(s.al, al, 1e-10 * al);
  EXPECT_NEAR(s.anll, anll, 1e-10);
  EXPECT_GT(s.ade_mixture, s.ade_nearest);
}

TEST(ScorePrediction, RejectsBadInput) {
  const TrajectoryDistribution d = Distribution(2);
  Eigen::MatrixX2d truth = Eigen::MatrixX2d::Zero(kSteps, 2);
  ExpectErrorContains([&] { ScorePrediction(d, truth, 0.0); }, {"dt", "0"});
  ExpectErrorContains([&] { ScorePrediction(d, Eigen::MatrixX2d(0, 2), kDt); }, {"no rows"});
  truth(3, 1) = std::nan("");
  ExpectErrorContains([&] { ScorePrediction(d, truth, kDt); }, {"truth", "row 3"});
}

TEST(ConstantVelocity, IsExactOnAStraightLine) {
  // x(t) = p0 + v t sampled every step; the last two observed points give v exactly.
  const Eigen::Vector2d p0(1.5, -0.5), v(0.35, -0.2);
  Eigen::MatrixX2d past(8, 2), future(kSteps, 2);
  for (int i = 0; i < 8; ++i) past.row(i) = (p0 + i * v).transpose();
  for (int i = 0; i < kSteps; ++i) future.row(i) = (p0 + (8 + i) * v).transpose();
  const Eigen::MatrixX2d cv = ConstantVelocity(past, kSteps);
  ASSERT_EQ(cv.rows(), kSteps);
  EXPECT_LT((cv - future).cwiseAbs().maxCoeff(), 1e-12);
  const PredictionScores s = ScorePoints(cv, future);
  EXPECT_NEAR(s.ade_nearest, 0.0, 1e-12);
  EXPECT_NEAR(s.fde_mixture, 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(s.al));
  EXPECT_TRUE(std::isnan(s.anll));
  ExpectErrorContains([&] { ConstantVelocity(past.topRows(1), 3); }, {">= 2", "1"});
  ExpectErrorContains([&] { ConstantVelocity(past, 0); }, {"f", "0"});
}

TEST(ScorePoints, MatchesHandComputedErrors) {
  Eigen::MatrixX2d predicted(3, 2), truth(3, 2);
  predicted << 0, 0, 1, 1, 2, 2;
  truth << 3, 4, 1, 2, 2, 2;  // errors 5, 1, 0
  const PredictionScores s = ScorePoints(predicted, truth);
  EXPECT_DOUBLE_EQ(s.ade_nearest, 2.0);
  EXPECT_DOUBLE_EQ(s.fde_nearest, 0.0);
  EXPECT_DOUBLE_EQ(s.ade_mixture, 2.0);
  ExpectErrorContains([&] { ScorePoints(predicted.topRows(2), truth); }, {"2 predicted", "3 true"});
}

TEST(Percentile, InterpolatesLinearly) {
  const std::vector<double> v = {3, 1, 2, 4};
  EXPECT_DOUBLE_EQ(Percentile(v, 0), 1.0);
  EXPECT_DOUBLE_EQ(Percentile(v, 100), 4.0);
  EXPECT_DOUBLE_EQ(Percentile(v, 50), 2.5);
  EXPECT_DOUBLE_EQ(Percentile(v, 25), 1.75);  // position 0.75 between 1 and 2
  EXPECT_DOUBLE_EQ(Percentile({7.0}, 99), 7.0);
  EXPECT_TRUE(std::isnan(Percentile({}, 50)));
  // Against the definition on a larger sample: p-th percentile of 0..100 is p.
  std::vector<double> w(101);
  for (int i = 0; i <= 100; ++i) w[static_cast<std::size_t>(100 - i)] = i;
  for (double q : {1.0, 37.5, 99.0}) EXPECT_NEAR(Percentile(w, q), q, 1e-12);
  ExpectErrorContains([&] { Percentile(v, 101); }, {"q", "101"});
  ExpectErrorContains([&] { Percentile({1.0, std::nan("")}, 50); }, {"NaN", "1"});
}

}  // namespace
}  // namespace foresight::constrained
