#include "core/von_mises.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/test_util.h"

namespace foresight {
namespace {

/// Periodic trapezoid rule over [-pi, pi) (spectrally accurate for smooth periodic integrands).
template <class F>
double IntegrateCircle(F f, int n) {
  double s = 0;
  for (int i = 0; i < n; ++i) s += f(-M_PI + 2 * M_PI * i / n);
  return s * 2 * M_PI / n;
}

TEST(VonMises, WrapAngleIsHalfOpen) {
  EXPECT_DOUBLE_EQ(WrapAngle(0.5), 0.5);
  EXPECT_NEAR(WrapAngle(0.5 + 6 * M_PI), 0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(-0.5 - 4 * M_PI), -0.5, 1e-12);
  EXPECT_DOUBLE_EQ(WrapAngle(M_PI), -M_PI);
  EXPECT_DOUBLE_EQ(WrapAngle(-M_PI), -M_PI);
  EXPECT_NEAR(WrapAngle(3 * M_PI / 2), -M_PI / 2, 1e-12);
  for (double t = -50; t < 50; t += 0.173) {
    const double w = WrapAngle(t);
    EXPECT_GE(w, -M_PI);
    EXPECT_LT(w, M_PI);
    EXPECT_NEAR(std::cos(w), std::cos(t), 1e-12);
    EXPECT_NEAR(std::sin(w), std::sin(t), 1e-12);
  }
}

TEST(VonMises, LogBesselI0MatchesStdCylBesselWhereFinite) {
  std::vector<double> ks = {0,    1e-10, 1e-3, 0.1, 0.5, 1,   2,   5,   10, 20,
                            29.9, 30,    30.1, 40,  75,  150, 300, 500, 700};
  for (double k : ks) {
    const double ref = std::log(std::cyl_bessel_i(0.0, k));
    EXPECT_NEAR(LogBesselI0(k), ref, 1e-13 * std::max(1.0, std::abs(ref))) << "kappa " << k;
    EXPECT_NEAR(LogBesselI0Scaled(k), ref - k, 1e-13 * std::max(1.0, k)) << "kappa " << k;
  }
  EXPECT_DOUBLE_EQ(LogBesselI0(0), 0.0);
}

TEST(VonMises, LogBesselI0MatchesLargeKappaExpansionBeyondOverflow) {
  // exp(kappa) overflows near 709; the scaled form stays finite. Independent reference:
  // log I0(k) = k - log(2 pi k)/2 + log(1 + 1/(8k) + 9/(128 k^2) + 225/(3072 k^3)) + O(k^-4).
  for (double k : {710.0, 1e3, 1e4, 1e6, 1e9, 1e15, 1e300}) {
    const double ref_scaled =
        -0.5 * std::log(2 * M_PI * k) +
        std::log1p(1 / (8 * k) + 9 / (128 * k * k) + 225 / (3072 * k * k * k));
    EXPECT_NEAR(LogBesselI0Scaled(k), ref_scaled, 1e-12 * std::abs(ref_scaled)) << k;
    EXPECT_TRUE(std::isfinite(LogBesselI0(k))) << k;
    EXPECT_NEAR(LogBesselI0(k), k + ref_scaled, 1e-15 * k + 1e-12) << k;
  }
  // Continuity across the series / asymptotic switch.
  EXPECT_NEAR(LogBesselI0(30.0 - 1e-9), LogBesselI0(30.0 + 1e-9), 1e-8);
}

TEST(VonMises, NegativeOrNanKappaIsAnError) {
  testing::ExpectErrorContains([] { LogBesselI0(-1); }, {"kappa -1", "non-negative"});
  testing::ExpectErrorContains([] { BesselRatioA1(std::nan("")); }, {"BesselRatioA1", "kappa"});
  testing::ExpectErrorContains([] { InverseA1(1.5); }, {"InverseA1", "1.5", "[0, 1]"});
  testing::ExpectErrorContains([] { VonMisesLogDensity(0, 0, -2); }, {"kappa -2"});
}

TEST(VonMises, A1MatchesStdCylBesselRatio) {
  for (double k : {1e-6, 0.01, 0.3, 1.0, 3.0, 10.0, 29.0, 31.0, 60.0, 200.0, 650.0}) {
    const double ref = std::cyl_bessel_i(1.0, k) / std::cyl_bessel_i(0.0, k);
    EXPECT_NEAR(BesselRatioA1(k), ref, 1e-14) << k;
  }
  EXPECT_DOUBLE_EQ(BesselRatioA1(0), 0.0);
  // Large kappa: A1 = 1 - 1/(2k) - 1/(8k^2) - 1/(8k^3) - 25/(128k^4) + O(k^-5).
  for (double k : {1e3, 1e5, 1e8}) {
    const double k2 = k * k;
    EXPECT_NEAR(BesselRatioA1(k),
                1 - 1 / (2 * k) - 1 / (8 * k2) - 1 / (8 * k2 * k) - 25 / (128 * k2 * k2), 1e-14)
        << k;
  }
  // Derivative against central finite differences.
  for (double k : {0.0, 0.2, 2.0, 25.0, 35.0, 400.0}) {
    const double h = std::max(1e-5, 1e-5 * k);
    const double lo = std::max(0.0, k - h);
    const double fd = (BesselRatioA1(k + h) - BesselRatioA1(lo)) / (k + h - lo);
    EXPECT_NEAR(BesselRatioA1Derivative(k), fd, 1e-6 * std::max(1.0, std::abs(fd))) << k;
  }
}

TEST(VonMises, InverseA1InvertsA1) {
  for (double k : {1e-6, 1e-3, 0.1, 0.5, 1.0, 1.5, 2.5, 5.0, 12.0, 40.0, 100.0, 1e3, 1e4, 1e6}) {
    EXPECT_NEAR(InverseA1(BesselRatioA1(k)), k, 1e-8 * k) << k;
  }
  for (double r : {0.0, 0.1, 0.52, 0.53, 0.84, 0.85, 0.99, 0.999999}) {
    EXPECT_NEAR(BesselRatioA1(InverseA1(r)), r, 1e-14) << r;
  }
  EXPECT_EQ(InverseA1(0), 0.0);
  const double cap = InverseA1(1.0);
  EXPECT_TRUE(std::isfinite(cap));
  EXPECT_GT(cap, 1e11);
  EXPECT_EQ(InverseA1(1 - 1e-13), cap);
}

TEST(VonMises, DensityIntegratesToOneAndMatchesClosedForm) {
  for (double k : {0.0, 0.1, 1.0, 4.0, 30.0, 100.0, 1000.0, 5000.0}) {
    const double mu = 2.9;
    const double integral =
        IntegrateCircle([&](double t) { return std::exp(VonMisesLogDensity(t, mu, k)); }, 40000);
    EXPECT_NEAR(integral, 1.0, 1e-10) << k;
    if (k <= 700) {
      const double t = -2.0;
      const double closed = std::exp(k * std::cos(t - mu)) / (2 * M_PI * std::cyl_bessel_i(0.0, k));
      EXPECT_NEAR(std::exp(VonMisesLogDensity(t, mu, k)), closed, 1e-12 * closed + 1e-300) << k;
    }
  }
  EXPECT_NEAR(std::exp(VonMisesLogDensity(1.0, -1.0, 0)), 1 / (2 * M_PI), 1e-15);
  // Periodic in theta and mu.
  EXPECT_NEAR(VonMisesLogDensity(0.3 + 2 * M_PI, -3.0, 7.0),
              VonMisesLogDensity(0.3, -3.0 + 4 * M_PI, 7.0), 1e-12);
  // Far from the mode at huge kappa: finite, very negative.
  EXPECT_NEAR(VonMisesLogDensity(M_PI, 0, 1e6), -2e6 - std::log(2 * M_PI) - LogBesselI0Scaled(1e6),
              1e-6);
}

TEST(VonMises, MixtureDensityIntegratesToOneAndIsTheWeightedSum) {
  Eigen::VectorXd alpha(3), mu(3), kappa(3);
  alpha << 0.2, 0.5, 0.3;
  mu << -3.0, 0.4, 2.0;
  kappa << 2.0, 50.0, 800.0;
  const double integral = IntegrateCircle(
      [&](double t) { return std::exp(VonMisesMixtureLogDensity(t, alpha, mu, kappa)); }, 40000);
  EXPECT_NEAR(integral, 1.0, 1e-10);
  for (double t : {-3.1, -1.0, 0.4, 2.05}) {
    double direct = 0;
    for (int r = 0; r < 3; ++r)
      direct += alpha[r] * std::exp(VonMisesLogDensity(t, mu[r], kappa[r]));
    EXPECT_NEAR(std::exp(VonMisesMixtureLogDensity(t, alpha, mu, kappa)), direct, 1e-12 * direct)
        << t;
  }
  // alpha = 0 components are absent; large kappa far from every mode stays finite in log space.
  Eigen::VectorXd a2(2), m2(2), k2(2);
  a2 << 1.0, 0.0;
  m2 << 0.0, 3.0;
  k2 << 1e5, 1e5;
  EXPECT_NEAR(VonMisesMixtureLogDensity(3.0, a2, m2, k2), VonMisesLogDensity(3.0, 0.0, 1e5), 1e-9);
  EXPECT_TRUE(std::isfinite(VonMisesMixtureLogDensity(3.0, a2, m2, k2)));
  testing::ExpectErrorContains([&] { VonMisesMixtureLogDensity(0, a2, mu, k2); },
                               {"alpha [2]", "mu [3]"});
}

TEST(VonMises, SamplerMeanResultantLengthIsA1) {
  std::mt19937_64 rng(11);
  const int n = 40000;
  for (double k : {0.0, 0.3, 1.0, 3.0, 20.0, 300.0, 2e6}) {
    const double mu = -2.5;
    double c = 0, s = 0;
    for (int i = 0; i < n; ++i) {
      const double t = SampleVonMises(mu, k, &rng);
      ASSERT_GE(t, -M_PI);
      ASSERT_LT(t, M_PI);
      c += std::cos(t - mu);
      s += std::sin(t - mu);
    }
    // E[cos(theta - mu)] = A1(kappa), E[sin(theta - mu)] = 0; Var cos <= 1 - A1^2 ... bound by 1.
    const double sd = std::sqrt((1 - BesselRatioA1(k) * BesselRatioA1(k)) / n) + 1e-9;
    EXPECT_NEAR(c / n, BesselRatioA1(k), 5 * sd + 1e-6) << k;
    EXPECT_NEAR(s / n, 0.0, 5 / std::sqrt(static_cast<double>(n))) << k;
  }
}

TEST(VonMises, SamplerMatchesTheDensityHistogram) {
  std::mt19937_64 rng(5);
  const double mu = 3.0, k = 2.0;
  const int n = 100000, bins = 20;
  std::vector<int> count(bins, 0);
  for (int i = 0; i < n; ++i) {
    const double t = SampleVonMises(mu, k, &rng);
    ++count[std::min(bins - 1, static_cast<int>((t + M_PI) / (2 * M_PI) * bins))];
  }
  for (int b = 0; b < bins; ++b) {
    const double lo = -M_PI + 2 * M_PI * b / bins, w = 2 * M_PI / bins;
    double p = 0;
    for (int j = 0; j < 200; ++j)
      p += std::exp(VonMisesLogDensity(lo + w * (j + 0.5) / 200, mu, k)) * w / 200;
    EXPECT_NEAR(count[b] / static_cast<double>(n), p, 5 * std::sqrt(p * (1 - p) / n) + 1e-4) << b;
  }
}

TEST(VonMises, FitRecoversParametersFromSamples) {
  std::mt19937_64 rng(3);
  for (double k : {0.5, 2.0, 15.0, 200.0}) {
    const double mu = 3.0;  // near the wrap point
    Eigen::VectorXd theta(20000);
    for (Eigen::Index i = 0; i < theta.size(); ++i) theta[i] = SampleVonMises(mu, k, &rng);
    const VonMisesFit fit = FitVonMises(theta, Eigen::VectorXd::Ones(theta.size()));
    EXPECT_NEAR(std::abs(WrapAngle(fit.mu - mu)), 0.0, 4 / std::sqrt(k * theta.size()) + 1e-3) << k;
    EXPECT_NEAR(fit.kappa, k, 0.06 * k) << k;
  }
}

TEST(VonMises, WeightedFitEqualsRepeatedSamples) {
  Eigen::VectorXd theta(3), w(3), rep(6);
  theta << 0.1, 0.5, -3.0;
  w << 1, 2, 3;
  rep << 0.1, 0.5, 0.5, -3.0, -3.0, -3.0;
  const VonMisesFit a = FitVonMises(theta, w), b = FitVonMises(rep, Eigen::VectorXd::Ones(6));
  EXPECT_NEAR(a.mu, b.mu, 1e-12);
  EXPECT_NEAR(a.kappa, b.kappa, 1e-9);
  // Hand check: the ML kappa solves A1(kappa) = R.
  const double c = std::cos(0.1) + 2 * std::cos(0.5) + 3 * std::cos(-3.0);
  const double s = std::sin(0.1) + 2 * std::sin(0.5) + 3 * std::sin(-3.0);
  EXPECT_NEAR(a.mu, std::atan2(s, c), 1e-12);
  EXPECT_NEAR(BesselRatioA1(a.kappa), std::hypot(c, s) / 6, 1e-13);
  // Identical angles: R = 1 -> the finite cap.
  const VonMisesFit same = FitVonMises(Eigen::VectorXd::Constant(4, 1.0), Eigen::VectorXd::Ones(4));
  EXPECT_TRUE(std::isfinite(same.kappa));
  EXPECT_NEAR(same.mu, 1.0, 1e-12);
  testing::ExpectErrorContains([&] { FitVonMises(theta, Eigen::VectorXd::Zero(3)); }, {"sum to 0"});
  testing::ExpectErrorContains([&] { FitVonMises(theta, -w); }, {"weight 0", "-1"});
  testing::ExpectErrorContains([&] { FitVonMises(theta, Eigen::VectorXd::Ones(2)); },
                               {"theta [3]", "weight [2]"});
}

TEST(VonMises, AverageLikelihoodAndMinimumRotationErrorByHand) {
  VonMisesMixtureBatch m;
  m.Resize(3, 2);
  // Query 0: uniform (kappa 0) -> density 1/(2 pi).
  m.alpha.row(0) << 1.0, 0.0;
  m.mu.row(0) << 0.25, 1.0;
  m.kappa.row(0) << 0.0, 3.0;
  // Query 1: two components; heading pi - 0.05 is 0.1 rad from mu = -pi + 0.05 across the wrap.
  m.alpha.row(1) << 0.25, 0.75;
  m.mu.row(1) << -M_PI + 0.05, 0.0;
  m.kappa.row(1) << 1.0, 2.0;
  // Query 2: one component exactly at the heading.
  m.alpha.row(2) << 0.0, 1.0;
  m.mu.row(2) << -1.0, 1.5;
  m.kappa.row(2) << 1.0, 4.0;
  Eigen::VectorXd theta(3);
  theta << 2.0, M_PI - 0.05, 1.5;

  auto vm = [](double t, double mu, double k) {
    return std::exp(k * std::cos(t - mu)) / (2 * M_PI * std::cyl_bessel_i(0.0, k));
  };
  const double p0 = 1 / (2 * M_PI);
  const double p1 = 0.25 * vm(M_PI - 0.05, -M_PI + 0.05, 1.0) + 0.75 * vm(M_PI - 0.05, 0.0, 2.0);
  const double p2 = vm(1.5, 1.5, 4.0);
  EXPECT_NEAR(AverageLikelihood(m, theta), (p0 + p1 + p2) / 3, 1e-14);
  // MRE: query 0 only has its alpha>0 component at 0.25 -> 1.75; query 1 -> 0.1 (wrapped, the
  // printed unwrapped |theta - mu| would give 2 pi - 0.1 for that component and pick pi - 0.05);
  // query 2 -> 0 (the alpha = 0 component at -1.0 is ignored).
  EXPECT_NEAR(MinimumRotationError(m, theta), (1.75 + 0.1 + 0.0) / 3, 1e-12);

  Eigen::VectorXd short_theta(2);
  testing::ExpectErrorContains([&] { AverageLikelihood(m, short_theta); },
                               {"AverageLikelihood", "2 headings"});
  m.alpha.row(2).setZero();
  testing::ExpectErrorContains([&] { MinimumRotationError(m, theta); },
                               {"mixture 2", "positive alpha"});
}

TEST(VonMises, MinimumRotationErrorWithMinWeightByHand) {
  VonMisesMixtureBatch m;
  m.Resize(4, 3);
  m.kappa.setConstant(5.0);
  // Row 0: a light component (0.05) sits on the heading; the heavy ones are 0.5 and 1.0 away.
  m.alpha.row(0) << 0.05, 0.55, 0.40;
  m.mu.row(0) << 1.0, 1.5, 2.0;
  // Row 1: every component is light (0.2 < 0.25): only the heaviest (the second) counts.
  m.alpha.row(1) << 0.20, 0.20, 0.20;  // ties: the first of the largest, column 0
  m.mu.row(1) << -3.0, 0.3, 0.1;
  // Row 2: a component exactly at the threshold counts (alpha < min_weight is dropped).
  m.alpha.row(2) << 0.25, 0.75, 0.0;
  m.mu.row(2) << 0.0, 2.0, 0.0;
  // Row 3: heading across the wrap from the heavy component; alpha 0 never counts.
  m.alpha.row(3) << 0.9, 0.1, 0.0;
  m.mu.row(3) << -M_PI + 0.1, M_PI - 0.2, M_PI - 0.3;
  Eigen::VectorXd theta(4);
  theta << 1.0, 0.0, 0.1, M_PI - 0.3;

  // min_weight 0: the plain MRE. Row 0: 0; row 1: min(3, 0.3, 0.1) = 0.1; row 2: 0.1 (mu 0);
  // row 3: |wrap(pi - 0.3 - (-pi + 0.1))| = 0.4, |pi - 0.3 - (pi - 0.2)| = 0.1 -> 0.1.
  const double plain = (0.0 + 0.1 + 0.1 + 0.1) / 4;
  EXPECT_NEAR(MinimumRotationError(m, theta, 0.0), plain, 1e-12);
  EXPECT_NEAR(MinimumRotationError(m, theta), plain, 1e-12);
  // min_weight 0.25. Row 0: the 0.05 component drops -> min(0.5, 1.0) = 0.5; row 1: only column 0
  // (the first heaviest) -> |0 - (-3)| = 3; row 2: 0.25 is not below 0.25 -> 0.1; row 3: the 0.1
  // component drops -> 0.4.
  EXPECT_NEAR(MinimumRotationError(m, theta, 0.25), (0.5 + 3.0 + 0.1 + 0.4) / 4, 1e-12);
  // min_weight 1: only the heaviest component of each row: 0.5, 3, |0.1 - 2| = 1.9, 0.4.
  EXPECT_NEAR(MinimumRotationError(m, theta, 1.0), (0.5 + 3.0 + 1.9 + 0.4) / 4, 1e-12);
  testing::ExpectErrorContains([&] { MinimumRotationError(m, theta, -0.1); },
                               {"min_weight -0.1", "[0, 1]"});
  testing::ExpectErrorContains([&] { MinimumRotationError(m, theta, 1.5); }, {"min_weight 1.5"});
  m.alpha.row(2).setZero();
  testing::ExpectErrorContains([&] { MinimumRotationError(m, theta, 0.5); },
                               {"mixture 2", "positive alpha"});
}

TEST(VonMises, CapConcentrationClampsKappaAndSetsTheAverageLikelihoodScale) {
  VonMisesMixtureBatch m;
  m.Resize(2, 2);
  m.alpha << 0.5, 0.5, 1.0, 0.0;
  m.mu << 0.0, 1.0, -0.5, 2.0;
  m.kappa << 500.0, 3.0, 100.0, 1e9;
  const VonMisesMixtureBatch before = m;
  CapConcentration(&m, 100.0);
  Eigen::MatrixXd expect(2, 2);
  expect << 100.0, 3.0, 100.0, 100.0;
  EXPECT_EQ(m.kappa, expect);
  EXPECT_EQ(m.alpha, before.alpha);
  EXPECT_EQ(m.mu, before.mu);
  CapConcentration(&m, 10.0);
  expect << 10.0, 3.0, 10.0, 10.0;
  EXPECT_EQ(m.kappa, expect);
  // AL at the cap against the closed form: each row's heading on its first component's mean.
  Eigen::VectorXd theta(2);
  theta << 0.0, -0.5;
  auto vm = [](double t, double mu, double k) {
    return std::exp(k * std::cos(t - mu)) / (2 * M_PI * std::cyl_bessel_i(0.0, k));
  };
  const double p0 = 0.5 * vm(0.0, 0.0, 10.0) + 0.5 * vm(0.0, 1.0, 3.0);
  const double p1 = vm(-0.5, -0.5, 10.0);
  EXPECT_NEAR(AverageLikelihood(m, theta), (p0 + p1) / 2, 1e-12);
  testing::ExpectErrorContains([&] { CapConcentration(&m, 0.0); }, {"cap 0", "> 0"});
  testing::ExpectErrorContains([&] { CapConcentration(&m, std::nan("")); }, {"cap nan"});
  testing::ExpectErrorContains([&] { CapConcentration(nullptr, 1.0); }, {"CapConcentration"});
}

}  // namespace
}  // namespace foresight
