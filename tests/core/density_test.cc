// One generic test suite that every probability density of core/ runs (STYLE.md, manif's habit):
//   - it integrates to one (midpoint quadrature over its support),
//   - samples have the moments the density implies (first and second, or trigonometric on the
//     circle), within five standard errors,
//   - a mixture's log density is the log-sum-exp of its weighted components.
// Each density is an adapter below; a new density adds one and joins the type list.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "core/matrix_normal.h"
#include "core/von_mises.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

/// 2-D Gaussian N(mu, Sigma) through LogGaussian2; samples by its Cholesky factor.
struct Gaussian2Case {
  static constexpr const char* kName = "Gaussian2";
  static constexpr bool kProductionSampler = false;  // core/ has no Gaussian sampler of its own
  Eigen::Vector2d mu{0.7, -1.2};
  Eigen::Matrix2d cov = (Eigen::Matrix2d() << 0.8, 0.3, 0.3, 0.5).finished();

  int Dim() const { return 2; }
  bool Periodic() const { return false; }
  Eigen::VectorXd Lower() const { return mu.array() - 9.0 * cov.diagonal().array().sqrt(); }
  Eigen::VectorXd Upper() const { return mu.array() + 9.0 * cov.diagonal().array().sqrt(); }
  double LogPdf(const Eigen::VectorXd& x) const { return LogGaussian2(x, mu, cov); }
  Eigen::VectorXd Sample(std::mt19937_64* rng) const {
    std::normal_distribution<double> n01;
    const Eigen::Matrix2d l = cov.llt().matrixL();
    return mu + l * Eigen::Vector2d(n01(*rng), n01(*rng));
  }
  /// Moment features (x, x x') and their expectations (mu, Sigma + mu mu').
  Eigen::VectorXd Features(const Eigen::VectorXd& x) const { return SecondMoments(x); }
  Eigen::VectorXd ExpectedFeatures() const { return ExpectedSecondMoments(mu, cov); }
  bool IsMixture() const { return false; }

  static Eigen::VectorXd SecondMoments(const Eigen::VectorXd& x) {
    const Eigen::Index d = x.size();
    Eigen::VectorXd f(d + d * d);
    f.head(d) = x;
    const Eigen::MatrixXd outer = x * x.transpose();
    f.tail(d * d) = Eigen::Map<const Eigen::VectorXd>(outer.data(), d * d);
    return f;
  }
  static Eigen::VectorXd ExpectedSecondMoments(const Eigen::VectorXd& mean,
                                               const Eigen::MatrixXd& cov) {
    const Eigen::Index d = mean.size();
    Eigen::VectorXd f(d + d * d);
    f.head(d) = mean;
    const Eigen::MatrixXd second = cov + mean * mean.transpose();
    f.tail(d * d) = Eigen::Map<const Eigen::VectorXd>(second.data(), d * d);
    return f;
  }
};

/// Matrix normal over W [1 x 2] (vec(W) ~ N(vec(M), V kron U)), so its density is a 2-D one that
/// quadrature can integrate; samples through MatrixNormal::Sample.
struct MatrixNormalCase {
  static constexpr const char* kName = "MatrixNormal";
  static constexpr bool kProductionSampler = true;
  MatrixNormal d = [] {
    MatrixNormal m;
    m.mean = (Eigen::MatrixXd(1, 2) << 0.4, -0.6).finished();
    m.chol_u = (Eigen::MatrixXd(1, 1) << 0.8).finished();
    m.chol_v << 1.1, 0.0, 0.4, 0.7;
    return m;
  }();

  int Dim() const { return 2; }
  bool Periodic() const { return false; }
  Eigen::Matrix2d Cov() const {
    const double u = d.chol_u(0, 0) * d.chol_u(0, 0);
    return u * d.chol_v * d.chol_v.transpose();
  }
  Eigen::VectorXd Lower() const { return Mean().array() - 9.0 * Cov().diagonal().array().sqrt(); }
  Eigen::VectorXd Upper() const { return Mean().array() + 9.0 * Cov().diagonal().array().sqrt(); }
  Eigen::Vector2d Mean() const { return d.mean.row(0).transpose(); }
  double LogPdf(const Eigen::VectorXd& x) const { return d.LogPdf(x.transpose()); }
  Eigen::VectorXd Sample(std::mt19937_64* rng) const { return d.Sample(rng).row(0).transpose(); }
  Eigen::VectorXd Features(const Eigen::VectorXd& x) const {
    return Gaussian2Case::SecondMoments(x);
  }
  Eigen::VectorXd ExpectedFeatures() const {
    return Gaussian2Case::ExpectedSecondMoments(Mean(), Cov());
  }
  bool IsMixture() const { return false; }
};

/// Three-component von Mises mixture on [-pi, pi): trigonometric moments
/// E[cos k theta], E[sin k theta] = sum_r alpha_r A_k(kappa_r) (cos k mu_r, sin k mu_r) for k = 1,
/// with A_1 = I1 / I0 (BesselRatioA1).
struct VonMisesMixtureCase {
  static constexpr const char* kName = "VonMisesMixture";
  static constexpr bool kProductionSampler = true;  // SampleVonMises per component
  Eigen::Vector3d alpha{0.5, 0.3, 0.2}, mu{-2.5, 0.4, 2.9}, kappa{4.0, 0.5, 30.0};

  int Dim() const { return 1; }
  bool Periodic() const { return true; }
  Eigen::VectorXd Lower() const { return Eigen::VectorXd::Constant(1, -M_PI); }
  Eigen::VectorXd Upper() const { return Eigen::VectorXd::Constant(1, M_PI); }
  double LogPdf(const Eigen::VectorXd& x) const {
    return VonMisesMixtureLogDensity(x[0], alpha, mu, kappa);
  }
  Eigen::VectorXd Sample(std::mt19937_64* rng) const {
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const double u = u01(*rng);
    int r = 0;
    for (double acc = alpha[0]; r < 2 && u >= acc; acc += alpha[++r]) {
    }
    return Eigen::VectorXd::Constant(1, SampleVonMises(mu[r], kappa[r], rng));
  }
  Eigen::VectorXd Features(const Eigen::VectorXd& x) const {
    return Eigen::Vector2d(std::cos(x[0]), std::sin(x[0]));
  }
  Eigen::VectorXd ExpectedFeatures() const {
    Eigen::Vector2d e = Eigen::Vector2d::Zero();
    for (int r = 0; r < 3; ++r)
      e += alpha[r] * BesselRatioA1(kappa[r]) * Eigen::Vector2d(std::cos(mu[r]), std::sin(mu[r]));
    return e;
  }
  bool IsMixture() const { return true; }
  /// log of each weighted component alpha_r p_r(x).
  Eigen::VectorXd WeightedComponentLogs(const Eigen::VectorXd& x) const {
    Eigen::VectorXd v(3);
    for (int r = 0; r < 3; ++r)
      v[r] = std::log(alpha[r]) + VonMisesLogDensity(x[0], mu[r], kappa[r]);
    return v;
  }
};

/// Midpoint rule over the box [lower, upper] with n points per dimension (1-D or 2-D): exact to
/// spectral accuracy for smooth periodic integrands, and to ~1e-6 for Gaussians within 9 sigma.
double Integrate(const std::function<double(const Eigen::VectorXd&)>& f,
                 const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, int n) {
  const Eigen::VectorXd h = (upper - lower) / n;
  double sum = 0;
  Eigen::VectorXd x(lower.size());
  if (lower.size() == 1) {
    for (int i = 0; i < n; ++i) sum += f(Eigen::VectorXd::Constant(1, lower[0] + (i + 0.5) * h[0]));
    return sum * h[0];
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      x << lower[0] + (i + 0.5) * h[0], lower[1] + (j + 0.5) * h[1];
      sum += f(x);
    }
  return sum * h[0] * h[1];
}

template <typename Case>
class DensitySuite : public ::testing::Test {
 protected:
  Case density;
};

using Densities = ::testing::Types<Gaussian2Case, MatrixNormalCase, VonMisesMixtureCase>;
struct DensityNames {
  template <typename T>
  static std::string GetName(int) {
    return T::kName;
  }
};
TYPED_TEST_SUITE(DensitySuite, Densities, DensityNames);

TYPED_TEST(DensitySuite, IntegratesToOne) {
  const auto& d = this->density;
  const int n = d.Dim() == 1 ? 20000 : 600;
  const double mass = Integrate([&](const Eigen::VectorXd& x) { return std::exp(d.LogPdf(x)); },
                                d.Lower(), d.Upper(), n);
  EXPECT_NEAR(mass, 1.0, 1e-6);
}

TYPED_TEST(DensitySuite, SamplesHaveTheImpliedMoments) {
  const auto& d = this->density;
  const Eigen::VectorXd expected = d.ExpectedFeatures();
  // The moments by quadrature of the density: the density has the law's moments.
  for (Eigen::Index k = 0; k < expected.size(); ++k) {
    const double by_quadrature = Integrate(
        [&](const Eigen::VectorXd& x) { return d.Features(x)[k] * std::exp(d.LogPdf(x)); },
        d.Lower(), d.Upper(), d.Dim() == 1 ? 20000 : 600);
    EXPECT_NEAR(by_quadrature, expected[k], 1e-5) << "moment feature " << k;
  }
  if (!TypeParam::kProductionSampler) GTEST_SKIP() << "no sampler of this density in core/";
  std::mt19937_64 rng(11);
  const int n = 200000;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(expected.size()),
                  sum_sq = Eigen::VectorXd::Zero(expected.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd x = d.Sample(&rng);
    ASSERT_EQ(x.size(), d.Dim());
    if (d.Periodic()) {
      ASSERT_GE(x[0], -M_PI);
      ASSERT_LT(x[0], M_PI);
    }
    const Eigen::VectorXd f = d.Features(x);
    sum += f;
    sum_sq += f.cwiseProduct(f);
  }
  const Eigen::VectorXd mean = sum / n;
  const Eigen::VectorXd std_error = ((sum_sq / n - mean.cwiseProduct(mean)) / n).cwiseSqrt();
  for (Eigen::Index k = 0; k < expected.size(); ++k)
    EXPECT_NEAR(mean[k], expected[k], 5.0 * std_error[k] + 1e-12) << "moment feature " << k;
}

TYPED_TEST(DensitySuite, MixtureIsTheLogSumExpOfItsComponents) {
  const auto& d = this->density;
  if constexpr (std::is_same_v<TypeParam, VonMisesMixtureCase>) {
    for (const double theta : {-3.0, -1.0, 0.0, 0.4, 2.9, 3.1})
      EXPECT_NEAR(d.LogPdf(Eigen::VectorXd::Constant(1, theta)),
                  LogSumExp(d.WeightedComponentLogs(Eigen::VectorXd::Constant(1, theta))), 1e-12);
  } else {
    GTEST_SKIP() << TypeParam::kName << " is not a mixture";
  }
}

// The matrix-normal mixture against its components (sizes above 1 x 2: a density over R^{m x 2}).
TEST(DensitySuiteMixtures, MatrixNormalMixtureIsTheLogSumExpOfItsComponents) {
  MatrixNormalMixture mix;
  mix.weights = {0.25, 0.75};
  for (int r = 0; r < 2; ++r) {
    MatrixNormal c;
    c.mean = Eigen::MatrixXd::Constant(3, 2, 0.3 * r);
    c.chol_u = (1.0 + r) * Eigen::MatrixXd::Identity(3, 3);
    c.chol_v << 1.0, 0.0, 0.2 * r, 0.5 + r;
    mix.components.push_back(c);
  }
  const Eigen::MatrixXd w = (Eigen::MatrixXd(3, 2) << 0.1, -0.2, 0.5, 0.3, -1.0, 0.8).finished();
  const Eigen::Vector2d logs(std::log(0.25) + mix.components[0].LogPdf(w),
                             std::log(0.75) + mix.components[1].LogPdf(w));
  EXPECT_NEAR(mix.LogPdf(w), LogSumExp(logs), 1e-12);
}

}  // namespace
}  // namespace foresight
