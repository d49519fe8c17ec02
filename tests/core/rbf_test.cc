#include "core/rbf.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "core/error.h"

namespace foresight {
namespace {

TEST(TimeBasis, EvaluatesSquaredExponential) {
  const TimeBasis b(5, 0.0, 4.0, 0.7);
  ASSERT_EQ(b.size(), 5);
  const Eigen::VectorXd phi = b.Evaluate(1.3);
  for (int j = 0; j < 5; ++j)
    EXPECT_NEAR(phi[j], std::exp(-0.7 * std::pow(1.3 - j * 1.0, 2)), 1e-15);
}

TEST(Ridge, MatchesAugmentedLeastSquaresByQr) {
  // Independent computation: min ||P w - y||^2 + lambda ||w||^2 == least squares on [P; sqrt(l) I].
  const TimeBasis b(8, 0.0, 4.8, 1.0);
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(13, 0.0, 4.8);
  Eigen::MatrixXd y(13, 2);
  for (int i = 0; i < 13; ++i) y.row(i) << std::sin(t[i]) + 0.3 * t[i], 0.5 * t[i] * t[i] - 1.0;
  const double lambda = 0.05;
  const Eigen::MatrixXd w = b.FitRidge(t, y, lambda);
  Eigen::MatrixXd a(13 + 8, 8);
  a << b.Design(t), std::sqrt(lambda) * Eigen::MatrixXd::Identity(8, 8);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(21, 2);
  rhs.topRows(13) = y;
  const Eigen::MatrixXd w_qr = a.colPivHouseholderQr().solve(rhs);
  EXPECT_LT((w - w_qr).norm(), 1e-9 * (1 + w.norm()));
}

TEST(Ridge, RecoversSmoothTrajectoriesAtTheSampleTimes) {
  // Centres with a one-second margin beyond both ends (models/span/span_data.cc).
  const TimeBasis b(8, -1.0, 5.8, 1.0);
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(13, 0.0, 4.8);
  Eigen::MatrixXd y(13, 2);
  for (int i = 0; i < 13; ++i)
    y.row(i) << 1.2 * t[i], 0.3 * std::sin(0.8 * t[i]);  // walking, slight sway
  const Eigen::MatrixXd w = b.FitRidge(t, y, 1e-4);
  const Eigen::MatrixXd fit = b.Design(t) * w;
  EXPECT_LT((fit - y).cwiseAbs().maxCoeff(), 0.01);  // sub-centimetre reconstruction
  // Without the margin the ends are off by more than 10 cm: the reason for the margin.
  const TimeBasis inner(8, 0.0, 4.8, 1.0);
  EXPECT_GT((inner.Design(t) * inner.FitRidge(t, y, 1e-4) - y).cwiseAbs().maxCoeff(), 0.1);
}

TEST(Ridge, BadInputIsAnError) {
  EXPECT_THROW(TimeBasis(0, 0.0, 1.0, 1.0), Error);
  EXPECT_THROW(TimeBasis(3, 0.0, 1.0, -1.0), Error);
  EXPECT_THROW(TimeBasis(3, 0.0, 1.0, 1.0)
                   .FitRidge(Eigen::VectorXd::Zero(2), Eigen::MatrixXd::Zero(2, 2), -1.0),
               Error);
}

}  // namespace
}  // namespace foresight
