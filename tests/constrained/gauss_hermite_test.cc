// Gauss-Hermite rules against closed forms: the small-n tables, the moments int x^k exp(-x^2) dx,
// the classical weight formula through the unnormalised Hermite recurrence, and the standard-normal
// moments of the 2-D tensor rule.

#include "inference/constrained/gauss_hermite.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "tests/test_util.h"

namespace foresight::constrained {
namespace {

const double kSqrtPi = std::sqrt(M_PI);

// int x^k exp(-x^2) dx over R: 0 for odd k, Gamma((k + 1) / 2) for even k.
double HermiteMoment(int k) { return k % 2 == 1 ? 0.0 : std::tgamma(0.5 * (k + 1)); }

// Physicists' H_n(x) by H_{j+1} = 2 x H_j - 2 j H_{j-1} (independent of the implementation's
// orthonormal recurrence).
double PhysicistsHermite(int n, double x) {
  double h0 = 1, h1 = 2 * x;
  if (n == 0) return h0;
  for (int j = 1; j < n; ++j) {
    const double h2 = 2 * x * h1 - 2 * j * h0;
    h0 = h1;
    h1 = h2;
  }
  return h1;
}

TEST(GaussHermite, SmallRulesMatchClosedForms) {
  const GaussHermiteRule r1 = GaussHermite(1);
  ASSERT_EQ(r1.nodes.size(), 1);
  EXPECT_NEAR(r1.nodes[0], 0.0, 1e-15);
  EXPECT_NEAR(r1.weights[0], kSqrtPi, 1e-14);

  const GaussHermiteRule r2 = GaussHermite(2);
  ASSERT_EQ(r2.nodes.size(), 2);
  EXPECT_NEAR(r2.nodes[0], -1 / std::sqrt(2.0), 1e-14);
  EXPECT_NEAR(r2.nodes[1], 1 / std::sqrt(2.0), 1e-14);
  EXPECT_NEAR(r2.weights[0], kSqrtPi / 2, 1e-14);
  EXPECT_NEAR(r2.weights[1], kSqrtPi / 2, 1e-14);

  const GaussHermiteRule r3 = GaussHermite(3);
  ASSERT_EQ(r3.nodes.size(), 3);
  EXPECT_NEAR(r3.nodes[0], -std::sqrt(1.5), 1e-14);
  EXPECT_NEAR(r3.nodes[1], 0.0, 1e-15);
  EXPECT_NEAR(r3.nodes[2], std::sqrt(1.5), 1e-14);
  EXPECT_NEAR(r3.weights[0], kSqrtPi / 6, 1e-14);
  EXPECT_NEAR(r3.weights[1], 2 * kSqrtPi / 3, 1e-14);
  EXPECT_NEAR(r3.weights[2], kSqrtPi / 6, 1e-14);
}

TEST(GaussHermite, RulesUpTo20AreExactForDegree2nMinus1) {
  for (int n = 1; n <= 20; ++n) {
    SCOPED_TRACE(n);
    const GaussHermiteRule r = GaussHermite(n);
    ASSERT_EQ(r.nodes.size(), n);
    ASSERT_EQ(r.weights.size(), n);
    EXPECT_NEAR(r.weights.sum(), kSqrtPi, 1e-13);
    for (int i = 0; i < n; ++i) {
      EXPECT_GT(r.weights[i], 0);
      if (i > 0) {
        EXPECT_LT(r.nodes[i - 1], r.nodes[i]);
      }
      EXPECT_EQ(r.nodes[i], -r.nodes[n - 1 - i]);  // symmetric
      EXPECT_EQ(r.weights[i], r.weights[n - 1 - i]);
    }
    for (int k = 0; k <= 2 * n - 1; ++k) {
      // Odd moments cancel between terms of size up to ~1e15 (k = 39): scale by sum |terms|.
      double sum = 0, magnitude = 0;
      for (int i = 0; i < n; ++i) {
        sum += r.weights[i] * std::pow(r.nodes[i], k);
        magnitude += std::abs(r.weights[i] * std::pow(r.nodes[i], k));
      }
      const double exact = HermiteMoment(k);
      EXPECT_NEAR(sum, exact, 1e-13 * std::max(1.0, magnitude)) << "x^" << k;
    }
    // Degree 2n is not integrated exactly (the rule really has n points).
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += r.weights[i] * std::pow(r.nodes[i], 2 * n);
    EXPECT_GT(std::abs(sum - HermiteMoment(2 * n)), 1e-6 * HermiteMoment(2 * n));
    // Nodes are roots of H_n and weights follow 2^{n-1} n! sqrt(pi) / (n^2 H_{n-1}(x_i)^2).
    for (int i = 0; i < n; ++i) {
      const double x = r.nodes[i];
      const double hm = PhysicistsHermite(n - 1, x);
      const double scale = 2.0 * n * std::abs(hm);  // |H_n'(x)| = 2 n |H_{n-1}(x)|
      EXPECT_LT(std::abs(PhysicistsHermite(n, x)) / scale, 1e-12) << "node " << i;
      const double w = std::pow(2.0, n - 1) * std::tgamma(n + 1.0) * kSqrtPi / (n * n * hm * hm);
      EXPECT_NEAR(r.weights[i], w, 1e-11 * w) << "weight " << i;
    }
  }
}

TEST(GaussHermite, LargestRuleIsAccurate) {
  const GaussHermiteRule r = GaussHermite(64);
  EXPECT_NEAR(r.weights.sum(), kSqrtPi, 1e-13);
  for (int k = 0; k <= 20; k += 2) {
    double sum = 0;
    for (int i = 0; i < 64; ++i) sum += r.weights[i] * std::pow(r.nodes[i], k);
    EXPECT_NEAR(sum, HermiteMoment(k), 1e-11 * HermiteMoment(k)) << "x^" << k;
  }
  EXPECT_TRUE((r.weights.array() > 0).all());
}

TEST(GaussHermite, StandardNormalRuleMoments) {
  for (int order = 1; order <= 12; ++order) {
    SCOPED_TRACE(order);
    const StandardNormalRule2 r = StandardNormalRule(order);
    ASSERT_EQ(r.size(), order * order);
    ASSERT_EQ(r.points.cols(), order * order);
    EXPECT_NEAR(r.weights.sum(), 1.0, 1e-14);
    const Eigen::Vector2d mean = r.points * r.weights;
    EXPECT_NEAR(mean.norm(), 0.0, 1e-14);
    if (order >= 2) {
      const Eigen::Matrix2d cov = r.points * r.weights.asDiagonal() * r.points.transpose();
      EXPECT_TRUE(testing::MatricesNear(cov, Eigen::Matrix2d::Identity(), 1e-13));
    }
    if (order >= 3) {
      double z1_4 = 0, z2_4 = 0, z1z2_2 = 0;
      for (int q = 0; q < r.size(); ++q) {
        z1_4 += r.weights[q] * std::pow(r.points(0, q), 4);
        z2_4 += r.weights[q] * std::pow(r.points(1, q), 4);
        z1z2_2 += r.weights[q] * std::pow(r.points(0, q) * r.points(1, q), 2);
      }
      EXPECT_NEAR(z1_4, 3.0, 1e-13);
      EXPECT_NEAR(z2_4, 3.0, 1e-13);
      EXPECT_NEAR(z1z2_2, 1.0, 1e-13);
    }
  }
}

// Dropping the lightest points in whole symmetry orbits up to a mass budget: none at order 4, about
// three quarters at order 32 (the kept counts were computed by a separate Golub-Welsch program with
// its own orbits). The kept rule stays symmetric (zero mean, isotropic covariance, the mirror of
// every kept point kept), and the expectation of any function in [0, 1] moves by at most the
// dropped mass, checked on half-plane indicators (the occupancy of a straight wall).
TEST(GaussHermite, PrunedRuleByMassKeepsSymmetryAndExpectationsOfProbabilities) {
  const std::map<int, int> kept_at_1e6 = {{4, 16},   {8, 60},   {12, 96}, {16, 132},
                                          {20, 164}, {24, 208}, {32, 276}};
  for (const auto& [order, kept] : kept_at_1e6) {
    SCOPED_TRACE(order);
    const StandardNormalRule2 full = StandardNormalRule(order);
    const StandardNormalRule2 r = PrunedRuleByMass(order, 1e-6);
    ASSERT_EQ(r.points.cols(), r.size());
    EXPECT_EQ(r.size(), kept);
    const double dropped = full.weights.sum() - r.weights.sum();
    EXPECT_GE(dropped, -1e-15);
    EXPECT_LE(dropped, 1e-6);
    // Symmetric: the mean vanishes and the covariance is isotropic (to rounding), and each kept
    // point's mirror images are kept.
    const Eigen::Vector2d mean = r.points * r.weights;
    EXPECT_LT(mean.norm(), 1e-14);
    const Eigen::Matrix2d cov = r.points * r.weights.asDiagonal() * r.points.transpose();
    EXPECT_NEAR(cov(0, 1), 0.0, 1e-14);
    EXPECT_NEAR(cov(0, 0), cov(1, 1), 1e-14);
    EXPECT_NEAR(cov(0, 0), 1.0, 1e-4);
    for (int q = 0; q < r.size(); ++q)
      for (const Eigen::Vector2d& m : {Eigen::Vector2d(-r.points(0, q), r.points(1, q)),
                                       Eigen::Vector2d(r.points(1, q), r.points(0, q))}) {
        double nearest = INFINITY;
        for (int k = 0; k < r.size(); ++k)
          nearest = std::min(nearest, (r.points.col(k) - m).norm());
        EXPECT_LT(nearest, 1e-12) << r.points.col(q).transpose();
      }
    for (double angle : {0.0, 0.7, 2.1})
      for (double offset : {-3.0, -1.0, 0.0, 0.5, 2.5, 4.0}) {
        const Eigen::Vector2d n(std::cos(angle), std::sin(angle));
        const auto wall = [&](const StandardNormalRule2& rule) {
          double e = 0;
          for (int q = 0; q < rule.size(); ++q)
            e += rule.weights[q] * (n.dot(rule.points.col(q)) > offset ? 1.0 : 0.0);
          return e;
        };
        EXPECT_LE(std::abs(wall(full) - wall(r)), dropped + 1e-15) << angle << " " << offset;
      }
  }
  EXPECT_EQ(PrunedRuleByMass(6, 0.0).size(), 36);
  for (double bad : {-1e-3, 1.0, std::nan("")})
    testing::ExpectErrorContains([bad] { PrunedRuleByMass(4, bad); },
                                 {"PrunedRuleByMass", "max_dropped_mass"});
  testing::ExpectErrorContains([] { PrunedRuleByMass(65, 1e-6); }, {"[1, 64]"});
}

TEST(GaussHermite, BadOrdersAreErrors) {
  for (int n : {0, -1, 65}) {
    testing::ExpectErrorContains([n] { GaussHermite(n); },
                                 {"GaussHermite", "[1, 64]", std::to_string(n)});
    testing::ExpectErrorContains([n] { StandardNormalRule(n); },
                                 {"StandardNormalRule", "order", std::to_string(n)});
  }
}

}  // namespace
}  // namespace foresight::constrained
