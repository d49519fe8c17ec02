// The matrix-normal KL divergence against the multivariate-Gaussian KL on the explicit 2m x 2m
// covariance of vec(W) (built entry by entry from Cov(W_ac, W_bd) = U_ab V_cd), its zero at p = p0,
// its sign, and its gradient against central finite differences.

#include "inference/constrained/kl.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "tests/test_util.h"

namespace foresight::constrained {
namespace {

using foresight::testing::ExpectErrorContains;

ComponentParams RandomComponent(int m, std::mt19937_64* rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  ComponentParams c;
  c.mean.resize(m, 2);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < 2; ++j) c.mean(i, j) = n01(*rng);
  c.log_u.resize(m);
  for (int i = 0; i < m; ++i) c.log_u[i] = 0.5 * n01(*rng);
  c.chol_v << std::exp(0.3 * n01(*rng)), 0, 0.5 * n01(*rng), std::exp(0.3 * n01(*rng));
  return c;
}

/// KL(N(mu, S) || N(mu0, S0)) on the explicit vec(W) ~ N(vec(M), V kron U), no structure used.
double ReferenceKl(const ComponentParams& p, const ComponentParams& p0) {
  const int m = p.basis();
  const auto covariance = [m](const ComponentParams& c) {
    const Eigen::Matrix2d v = c.chol_v * c.chol_v.transpose();
    const Eigen::VectorXd u = c.log_u.array().exp();
    Eigen::MatrixXd s = Eigen::MatrixXd::Zero(2 * m, 2 * m);
    // vec is column-major: W(a, col) sits at col * m + a; U is diagonal.
    for (int ca = 0; ca < 2; ++ca)
      for (int cb = 0; cb < 2; ++cb)
        for (int a = 0; a < m; ++a) s(ca * m + a, cb * m + a) = u[a] * v(ca, cb);
    return s;
  };
  const auto vec = [m](const ComponentParams& c) {
    Eigen::VectorXd x(2 * m);
    for (int col = 0; col < 2; ++col)
      for (int a = 0; a < m; ++a) x[col * m + a] = c.mean(a, col);
    return x;
  };
  const Eigen::MatrixXd s = covariance(p);
  const Eigen::MatrixXd s0 = covariance(p0);
  const Eigen::LLT<Eigen::MatrixXd> llt0(s0);
  const Eigen::LLT<Eigen::MatrixXd> llt(s);
  EXPECT_EQ(llt0.info(), Eigen::Success);
  EXPECT_EQ(llt.info(), Eigen::Success);
  const Eigen::VectorXd d = vec(p) - vec(p0);
  const double trace = llt0.solve(s).trace();
  const double quad = d.dot(llt0.solve(d));
  const double logdet0 = std::log(s0.determinant());
  const double logdet = std::log(s.determinant());
  return 0.5 * (trace + quad - 2.0 * m + logdet0 - logdet);
}

TEST(MatrixNormalKl, MatchesExplicitGaussianKl) {
  std::mt19937_64 rng(7);
  for (int m = 3; m <= 8; ++m) {
    for (int rep = 0; rep < 5; ++rep) {
      const ComponentParams p = RandomComponent(m, &rng);
      const ComponentParams p0 = RandomComponent(m, &rng);
      const double kl = MatrixNormalKl(p, p0, nullptr);
      const double ref = ReferenceKl(p, p0);
      EXPECT_NEAR(kl, ref, 1e-9 * (1.0 + std::abs(ref))) << "m = " << m;
      EXPECT_GT(kl, 0.0);
    }
  }
}

TEST(MatrixNormalKl, ZeroAtItselfAndNonNegative) {
  std::mt19937_64 rng(11);
  for (int m = 3; m <= 8; ++m) {
    const ComponentParams p = RandomComponent(m, &rng);
    ComponentGradient g;
    EXPECT_NEAR(MatrixNormalKl(p, p, &g), 0.0, 1e-12);
    // The minimum: the gradient vanishes there too.
    EXPECT_LT(g.ToVector(p).norm(), 1e-12);
    for (int rep = 0; rep < 20; ++rep) {
      ComponentParams q = p;
      std::normal_distribution<double> n01(0.0, 0.05);
      q.mean(rep % m, rep % 2) += n01(rng);
      q.log_u[rep % m] += n01(rng);
      q.chol_v(1, 0) += n01(rng);
      EXPECT_GE(MatrixNormalKl(q, p, nullptr), 0.0);
    }
  }
}

TEST(MatrixNormalKl, GradientMatchesCentralDifferences) {
  std::mt19937_64 rng(3);
  const double h = 1e-6;
  for (int m = 3; m <= 8; ++m) {
    const ComponentParams p = RandomComponent(m, &rng);
    const ComponentParams p0 = RandomComponent(m, &rng);
    ComponentGradient g;
    MatrixNormalKl(p, p0, &g);
    const auto fd = [&](const auto& perturb) {
      ComponentParams a = p;
      ComponentParams b = p;
      perturb(&a, h);
      perturb(&b, -h);
      return (MatrixNormalKl(a, p0, nullptr) - MatrixNormalKl(b, p0, nullptr)) / (2 * h);
    };
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < 2; ++j) {
        const double num = fd([i, j](ComponentParams* c, double d) { c->mean(i, j) += d; });
        EXPECT_NEAR(g.mean(i, j), num, 1e-6 * (1 + std::abs(num))) << "mean " << i << "," << j;
      }
      const double num = fd([i](ComponentParams* c, double d) { c->log_u[i] += d; });
      EXPECT_NEAR(g.log_u[i], num, 1e-6 * (1 + std::abs(num))) << "log_u " << i;
    }
    const int rows[3] = {0, 1, 1};
    const int cols[3] = {0, 0, 1};
    for (int e = 0; e < 3; ++e) {
      const int r = rows[e];
      const int c = cols[e];
      const double num = fd([r, c](ComponentParams* x, double d) { x->chol_v(r, c) += d; });
      EXPECT_NEAR(g.chol_v(r, c), num, 1e-6 * (1 + std::abs(num))) << "chol_v " << r << "," << c;
    }
    EXPECT_EQ(g.chol_v(0, 1), 0.0);
  }
}

TEST(MatrixNormalKl, ThetaGradientMatchesCentralDifferences) {
  // Through component.h's flat layout (the diagonal of L_V as a log), as the projection uses it.
  std::mt19937_64 rng(5);
  const int m = 5;
  const ComponentParams p = RandomComponent(m, &rng);
  const ComponentParams p0 = RandomComponent(m, &rng);
  ComponentGradient g;
  MatrixNormalKl(p, p0, &g);
  const Eigen::VectorXd grad = g.ToVector(p);
  const Eigen::VectorXd theta = p.ToVector();
  const double h = 1e-6;
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    Eigen::VectorXd a = theta;
    Eigen::VectorXd b = theta;
    a[i] += h;
    b[i] -= h;
    const double num = (MatrixNormalKl(ComponentParams::FromVector(a, m), p0, nullptr) -
                        MatrixNormalKl(ComponentParams::FromVector(b, m), p0, nullptr)) /
                       (2 * h);
    EXPECT_NEAR(grad[i], num, 1e-6 * (1 + std::abs(num))) << "theta " << i;
  }
}

TEST(MatrixNormalKl, RejectsMismatchedComponents) {
  std::mt19937_64 rng(1);
  const ComponentParams p = RandomComponent(3, &rng);
  const ComponentParams q = RandomComponent(4, &rng);
  ExpectErrorContains([&] { MatrixNormalKl(p, q, nullptr); }, {"MatrixNormalKl", "basis 3", "4"});
  ComponentParams bad = p;
  bad.chol_v(1, 1) = -1.0;
  ExpectErrorContains([&] { MatrixNormalKl(bad, p, nullptr); }, {"p.chol_v", "-1"});
  bad = p;
  bad.log_u.resize(2);
  ExpectErrorContains([&] { MatrixNormalKl(p, bad, nullptr); }, {"p0.log_u", "2 entries"});
}

}  // namespace
}  // namespace foresight::constrained
