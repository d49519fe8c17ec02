// Full-covariance BHM against a dense Eigen computation of the variational EM in information form.

#include "models/occupancy/bhm.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <tuple>

#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::occupancy {
namespace {

using testing::PointSet;

HingeGridConfig Tiny() {
  HingeGridConfig c;  // 4 x 3 features, every one within the cut-off of every point used
  c.x_min = 0;
  c.x_max = 2;
  c.y_min = 0;
  c.y_max = 1.5;
  c.spacing = 0.5;
  c.gamma = 1.5;
  c.cutoff_radius = 5.0;
  return c;
}

double RefLambda(double z) {
  return z == 0 ? 0.125 : (testing::ReferenceSigmoid(z) - 0.5) / (2 * z);
}

struct Gaussian {
  Eigen::VectorXd mu;
  Eigen::MatrixXd sigma;
};

Eigen::VectorXd RefBounds(const Eigen::MatrixXd& phi, const Gaussian& g) {
  Eigen::VectorXd z(phi.rows());
  for (Eigen::Index n = 0; n < phi.rows(); ++n) {
    const Eigen::VectorXd f = phi.row(n).transpose();
    z[n] = std::sqrt(f.dot(g.sigma * f) + std::pow(f.dot(g.mu), 2));
  }
  return z;
}

/// P = P0 + 2 Phi' diag(lambda) Phi,  mu = P^-1 (P0 mu0 + Phi' (y - 1/2)),  Sigma = P^-1.
Gaussian RefUpdate(const HingeGridConfig& c, const Gaussian& prior, const PointSet& p,
                   const FastBhmConfig& cfg) {
  const Eigen::MatrixXd phi = testing::DenseDesign(c, p.xy);
  Eigen::VectorXd y(p.xy.cols());
  for (Eigen::Index n = 0; n < y.size(); ++n) y[n] = p.occupied[n] ? 0.5 : -0.5;
  const Eigen::MatrixXd p0 = prior.sigma.inverse();
  Eigen::VectorXd z =
      cfg.bound_init == BoundInit::kOne ? Eigen::VectorXd::Ones(y.size()) : RefBounds(phi, prior);
  Gaussian post = prior;
  for (int it = 0; it < cfg.em_iterations; ++it) {
    if (it > 0) z = RefBounds(phi, post);
    Eigen::VectorXd lambda(z.size());
    for (Eigen::Index n = 0; n < z.size(); ++n) lambda[n] = RefLambda(z[n]);
    const Eigen::MatrixXd precision = p0 + 2.0 * phi.transpose() * lambda.asDiagonal() * phi;
    post.sigma = precision.inverse();
    post.mu = precision.partialPivLu().solve(p0 * prior.mu + phi.transpose() * y);
  }
  return post;
}

class BhmDense : public ::testing::TestWithParam<std::tuple<BoundInit, int>> {};

TEST_P(BhmDense, EqualsTheDenseInformationFormUpdate) {
  const HingeGridConfig c = Tiny();
  FastBhmConfig cfg;
  std::tie(cfg.bound_init, cfg.em_iterations) = GetParam();
  cfg.prior_mean = 0.4;
  cfg.prior_variance = 2.0;
  BhmLearner learner{HingeGrid(c), cfg};
  Gaussian ref{Eigen::VectorXd::Constant(12, 0.4), 2.0 * Eigen::MatrixXd::Identity(12, 12)};
  for (const auto& [n, seed] : {std::pair{4, 21}, std::pair{9, 22}, std::pair{6, 23}}) {
    const PointSet p = testing::RandomPoints(n, -0.3, 2.0, -0.3, 1.5, seed);
    learner.Update(p.xy, p.occupied.data());
    ref = RefUpdate(c, ref, p, cfg);
    const double scale = ref.sigma.cwiseAbs().maxCoeff();
    EXPECT_LT((learner.covariance() - ref.sigma).cwiseAbs().maxCoeff(), 1e-10 * scale);
    EXPECT_LT((learner.mean() - ref.mu).cwiseAbs().maxCoeff(),
              1e-10 * (1 + ref.mu.cwiseAbs().maxCoeff()));
  }
  // The full covariance couples the weights (what Fast-BHM drops).
  EXPECT_GT((ref.sigma - Eigen::MatrixXd(ref.sigma.diagonal().asDiagonal())).cwiseAbs().maxCoeff(),
            1e-3);
  const HingeMap map = learner.ToMap();
  EXPECT_EQ(map.kind(), HingeMapKind::kBhm);
  EXPECT_EQ(map.weights().covariance, learner.covariance());
  EXPECT_EQ(map.weights().variance, learner.covariance().diagonal());
  EXPECT_EQ(map.prior_mean(), 0.4);
  EXPECT_EQ(map.prior_variance(), 2.0);
}

INSTANTIATE_TEST_SUITE_P(BoundInitIterations, BhmDense,
                         ::testing::Values(std::tuple{BoundInit::kOne, 1},
                                           std::tuple{BoundInit::kPrior, 1},
                                           std::tuple{BoundInit::kOne, 2},
                                           std::tuple{BoundInit::kPrior, 3}));

TEST(Bhm, RefusesGridsTooLargeForADenseCovariance) {
  HingeGridConfig c = Tiny();
  c.x_max = 40;
  c.y_max = 30;
  c.cutoff_radius = 1.0;  // 80 x 60 = 4800 features
  testing::ExpectErrorContains([&] { BhmLearner(HingeGrid(c), FastBhmConfig{}); },
                               {"4800 features", "4096"});
}

}  // namespace
}  // namespace foresight::occupancy
