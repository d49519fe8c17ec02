#include "core/matrix_normal.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace foresight {
namespace {

/// Independent reference: vec(W) ~ N(vec(M), V kron U) with a dense covariance.
double KroneckerLogPdf(const MatrixNormal& d, const Eigen::MatrixXd& w) {
  const int m = d.rows();
  const Eigen::MatrixXd u = d.chol_u * d.chol_u.transpose();
  const Eigen::Matrix2d v = d.chol_v * d.chol_v.transpose();
  Eigen::MatrixXd cov(2 * m, 2 * m);
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) cov.block(a * m, b * m, m, m) = v(a, b) * u;
  Eigen::VectorXd x(2 * m), mu(2 * m);
  x << w.col(0), w.col(1);
  mu << d.mean.col(0), d.mean.col(1);
  Eigen::LLT<Eigen::MatrixXd> llt(cov);
  const Eigen::VectorXd z = llt.matrixL().solve(x - mu);
  const double log_det = 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
  return -0.5 * z.squaredNorm() - 0.5 * log_det - m * std::log(2 * M_PI);
}

MatrixNormal RandomMatrixNormal(int m, std::mt19937_64* rng) {
  std::normal_distribution<double> n01;
  MatrixNormal d;
  d.mean = Eigen::MatrixXd::NullaryExpr(m, 2, [&] { return n01(*rng); });
  d.chol_u = Eigen::MatrixXd::NullaryExpr(m, m, [&] {
               return 0.3 * n01(*rng);
             }).triangularView<Eigen::Lower>();
  for (int i = 0; i < m; ++i) d.chol_u(i, i) = std::exp(0.3 * n01(*rng));
  d.chol_v << std::exp(0.2 * n01(*rng)), 0, 0.5 * n01(*rng), std::exp(0.2 * n01(*rng));
  return d;
}

TEST(MatrixNormal, LogPdfMatchesKroneckerGaussian) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n01;
  for (int m : {1, 3, 8}) {
    for (int trial = 0; trial < 5; ++trial) {
      const MatrixNormal d = RandomMatrixNormal(m, &rng);
      const Eigen::MatrixXd w = Eigen::MatrixXd::NullaryExpr(m, 2, [&] { return n01(rng); });
      EXPECT_NEAR(d.LogPdf(w), KroneckerLogPdf(d, w), 1e-9) << "m=" << m;
    }
  }
}

TEST(MatrixNormal, PositionIsTheLinearMapOfTheKroneckerCovariance) {
  std::mt19937_64 rng(2);
  const int m = 5;
  const MatrixNormal d = RandomMatrixNormal(m, &rng);
  const Eigen::VectorXd phi = Eigen::VectorXd::Random(m);
  Eigen::Vector2d mu;
  Eigen::Matrix2d cov;
  d.Position(phi, &mu, &cov);
  // o = (I2 kron phi') vec(W): cov = A (V kron U) A'.
  const Eigen::MatrixXd u = d.chol_u * d.chol_u.transpose();
  const Eigen::Matrix2d v = d.chol_v * d.chol_v.transpose();
  Eigen::MatrixXd big(2 * m, 2 * m), a = Eigen::MatrixXd::Zero(2, 2 * m);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) big.block(i * m, j * m, m, m) = v(i, j) * u;
  a.block(0, 0, 1, m) = phi.transpose();
  a.block(1, m, 1, m) = phi.transpose();
  EXPECT_TRUE(cov.isApprox(a * big * a.transpose(), 1e-12));
  EXPECT_TRUE(mu.isApprox(d.mean.transpose() * phi, 1e-12));
}

TEST(MatrixNormal, SamplesMatchMoments) {
  std::mt19937_64 rng(3);
  const int m = 3;
  const MatrixNormal d = RandomMatrixNormal(m, &rng);
  const int n = 40000;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(2 * m);
  Eigen::MatrixXd sq = Eigen::MatrixXd::Zero(2 * m, 2 * m);
  for (int s = 0; s < n; ++s) {
    const Eigen::MatrixXd w = d.Sample(&rng);
    Eigen::VectorXd x(2 * m);
    x << w.col(0), w.col(1);
    sum += x;
    sq += x * x.transpose();
  }
  const Eigen::VectorXd mean = sum / n;
  const Eigen::MatrixXd cov = sq / n - mean * mean.transpose();
  Eigen::VectorXd mu(2 * m);
  mu << d.mean.col(0), d.mean.col(1);
  const Eigen::MatrixXd u = d.chol_u * d.chol_u.transpose();
  const Eigen::Matrix2d v = d.chol_v * d.chol_v.transpose();
  Eigen::MatrixXd expected(2 * m, 2 * m);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) expected.block(i * m, j * m, m, m) = v(i, j) * u;
  EXPECT_LT((mean - mu).cwiseAbs().maxCoeff(), 0.05 * std::sqrt(expected.diagonal().maxCoeff()));
  EXPECT_LT((cov - expected).cwiseAbs().maxCoeff(), 0.05 * expected.diagonal().maxCoeff());
}

TEST(MatrixNormal, MixtureIsLogSumOfComponents) {
  std::mt19937_64 rng(4);
  MatrixNormalMixture mix;
  mix.weights = {0.2, 0.5, 0.3};
  for (int r = 0; r < 3; ++r) mix.components.push_back(RandomMatrixNormal(4, &rng));
  const Eigen::MatrixXd w = Eigen::MatrixXd::Random(4, 2);
  double p = 0;
  for (int r = 0; r < 3; ++r) p += mix.weights[r] * std::exp(mix.components[r].LogPdf(w));
  EXPECT_NEAR(mix.LogPdf(w), std::log(p), 1e-10);
}

TEST(Gaussian2, MatchesDenseFormula) {
  Eigen::Matrix2d cov;
  cov << 2.0, 0.3, 0.3, 0.5;
  const Eigen::Vector2d x(0.4, -1.0), mu(0.1, 0.2);
  const Eigen::Vector2d d = x - mu;
  const double ref =
      -0.5 * d.dot(cov.inverse() * d) - std::log(2 * M_PI) - 0.5 * std::log(cov.determinant());
  EXPECT_NEAR(LogGaussian2(x, mu, cov), ref, 1e-12);
  EXPECT_NEAR(SquaredMahalanobis2(x, mu, cov), d.dot(cov.inverse() * d), 1e-12);
}

// The k-sigma ellipses hold 1 - exp(-k^2 / 2) of a 2-D Gaussian's mass (chi-square with 2 degrees
// of freedom): the calibration reference of the trajectory predictors.
TEST(Gaussian2, SigmaEllipsesHoldTheirChiSquareMass) {
  Eigen::Matrix2d cov;
  cov << 1.5, -0.6, -0.6, 0.7;
  const Eigen::Matrix2d l = cov.llt().matrixL();
  const Eigen::Vector2d mu(2.0, -1.0);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01;
  const int n = 100000;
  int one = 0, two = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d x = mu + l * Eigen::Vector2d(n01(rng), n01(rng));
    const double d2 = SquaredMahalanobis2(x, mu, cov);
    one += d2 <= 1.0;
    two += d2 <= 4.0;
  }
  // Binomial standard errors are ~0.0015 and ~0.0011; 4 of them.
  EXPECT_NEAR(static_cast<double>(one) / n, 1 - std::exp(-0.5), 0.006);
  EXPECT_NEAR(static_cast<double>(two) / n, 1 - std::exp(-2.0), 0.005);
}

}  // namespace
}  // namespace foresight
