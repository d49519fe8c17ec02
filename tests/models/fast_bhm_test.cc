// Fast-BHM against the published update computed densely and independently (thesis ch 3;
// spec/errata.md ch 3 for the exact M-step).

#include "models/occupancy/fast_bhm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::occupancy {
namespace {

using testing::PointSet;
using testing::RandomPoints;

HingeGridConfig TestGrid() { return testing::SmallGrid(4, 3, 2.5, 1.1); }  // 8 x 6 = 48 features

/// lambda straight from its definition (limit 1/8 at z = 0).
double RefLambda(double z) {
  if (z == 0) return 0.125;
  return (testing::ReferenceSigmoid(z) - 0.5) / (2 * z);
}

/// Mean-field state of every weight.
struct Dense {
  Eigen::VectorXd mu, s2;
};

/// z_n of every point from the state `st` (M-step, exact or as printed).
Eigen::VectorXd RefBounds(const Eigen::MatrixXd& phi, const Dense& st, MStepForm form) {
  const Eigen::MatrixXd phi2 = phi.cwiseAbs2();
  const Eigen::VectorXd mean = phi * st.mu;
  if (form == MStepForm::kExact) return (phi2 * st.s2 + mean.cwiseAbs2()).cwiseSqrt();
  return (phi2 * (st.s2 + st.mu.cwiseAbs2())).cwiseSqrt();
}

/// One scan of the published Fast-BHM update, dense:
///   1/s2 = 1/s20 + 2 sum_n lambda(z_n) phi^2,   mu = s2 (mu0 / s20 + sum_n (y_n - 1/2) phi).
Dense RefUpdate(const HingeGridConfig& c, const Dense& prior, const PointSet& p,
                const FastBhmConfig& cfg) {
  const Eigen::MatrixXd phi = testing::DenseDesign(c, p.xy);  // n x T
  Eigen::VectorXd y(p.xy.cols());
  for (Eigen::Index n = 0; n < y.size(); ++n) y[n] = p.occupied[n] ? 0.5 : -0.5;
  Eigen::VectorXd z = cfg.bound_init == BoundInit::kOne ? Eigen::VectorXd::Ones(y.size())
                                                        : RefBounds(phi, prior, cfg.m_step);
  Dense post = prior;
  for (int it = 0; it < cfg.em_iterations; ++it) {
    if (it > 0) z = RefBounds(phi, post, cfg.m_step);
    Eigen::VectorXd lambda(z.size());
    for (Eigen::Index n = 0; n < z.size(); ++n) lambda[n] = RefLambda(z[n]);
    const Eigen::VectorXd precision =
        prior.s2.cwiseInverse() + 2.0 * phi.cwiseAbs2().transpose() * lambda;
    post.s2 = precision.cwiseInverse();
    post.mu = post.s2.cwiseProduct(prior.mu.cwiseQuotient(prior.s2) + phi.transpose() * y);
  }
  return post;
}

void ExpectClose(const Eigen::VectorXd& got, const Eigen::VectorXd& want, double rel,
                 const std::string& what) {
  ASSERT_EQ(got.size(), want.size());
  for (Eigen::Index t = 0; t < got.size(); ++t)
    EXPECT_NEAR(got[t], want[t], rel * (std::abs(want[t]) + 1e-12)) << what << " weight " << t;
}

class FastBhmFormulas : public ::testing::TestWithParam<std::tuple<BoundInit, MStepForm, int>> {};

TEST_P(FastBhmFormulas, UpdatesEqualTheDensePublishedFormulas) {
  const HingeGridConfig c = TestGrid();
  FastBhmConfig cfg;
  std::tie(cfg.bound_init, cfg.m_step, cfg.em_iterations) = GetParam();
  cfg.prior_mean = 0.2;  // a non-zero prior mean makes every term of the update count
  cfg.prior_variance = 3.0;
  FastBhmLearner learner{HingeGrid(c), cfg};
  Dense ref{Eigen::VectorXd::Constant(48, 0.2), Eigen::VectorXd::Constant(48, 3.0)};
  // Three scans: a few points, one outside the grid's features (no effect), then more.
  for (const auto& [n, seed] : {std::pair{5, 1}, std::pair{7, 2}, std::pair{12, 3}}) {
    PointSet p = RandomPoints(n, -0.5, 4.0, -0.5, 3.0, seed);
    p.xy.col(0) << 30.0, -30.0;
    learner.Update(p.xy, p.occupied.data());
    ref = RefUpdate(c, ref, p, cfg);
    ExpectClose(learner.variance(), ref.s2, 1e-12, "variance");
    ExpectClose(learner.mean(), ref.mu, 1e-11, "mean");
  }
  // The map carries the weights and the configured prior.
  const HingeMap map = learner.ToMap();
  EXPECT_EQ(map.kind(), HingeMapKind::kFastBhm);
  EXPECT_EQ(map.weights().mean, learner.mean());
  EXPECT_EQ(map.weights().variance, learner.variance());
  EXPECT_EQ(map.prior_mean(), 0.2);
  EXPECT_EQ(map.prior_variance(), 3.0);
}

INSTANTIATE_TEST_SUITE_P(BoundInitMStepIterations, FastBhmFormulas,
                         ::testing::Values(std::tuple{BoundInit::kOne, MStepForm::kExact, 1},
                                           std::tuple{BoundInit::kPrior, MStepForm::kExact, 1},
                                           std::tuple{BoundInit::kPrior, MStepForm::kPrinted, 1},
                                           std::tuple{BoundInit::kOne, MStepForm::kExact, 2},
                                           std::tuple{BoundInit::kOne, MStepForm::kPrinted, 2},
                                           std::tuple{BoundInit::kPrior, MStepForm::kExact, 3}));

TEST(FastBhm, ExactAndPrintedMStepsDiffer) {
  // The test above can tell them apart only if they differ on its data.
  const HingeGridConfig c = TestGrid();
  FastBhmConfig exact, printed;
  exact.em_iterations = printed.em_iterations = 2;
  printed.m_step = MStepForm::kPrinted;
  const PointSet p = RandomPoints(20, 0, 4, 0, 3, 4);
  FastBhmLearner a{HingeGrid(c), exact}, b{HingeGrid(c), printed};
  a.Update(p.xy, p.occupied.data());
  b.Update(p.xy, p.occupied.data());
  EXPECT_GT((a.mean() - b.mean()).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(FastBhm, BoundInitOneStartsFromZEqualsOneOnTheFirstScan) {
  // The published formula for one point and bound_init one, written out for one weight.
  const HingeGridConfig c = TestGrid();
  FastBhmConfig cfg;
  cfg.prior_variance = 5.0;
  FastBhmLearner learner{HingeGrid(c), cfg};
  Eigen::Matrix2Xd xy(2, 1);
  xy << 1.1, 1.3;
  const std::uint8_t occ = 1;
  learner.Update(xy, &occ);
  const int t = 2 * 8 + 2;  // centre (1.0, 1.0)
  const double phi = std::exp(-2.5 * (0.1 * 0.1 + 0.3 * 0.3));
  const double lambda1 = (1.0 / (1.0 + std::exp(-1.0)) - 0.5) / 2.0;
  const double s2 = 1.0 / (1.0 / 5.0 + 2.0 * lambda1 * phi * phi);
  EXPECT_NEAR(learner.variance()[t], s2, 1e-13);
  EXPECT_NEAR(learner.mean()[t], s2 * 0.5 * phi, 1e-13);
}

TEST(JaakkolaLambda, MatchesDefinitionIsEvenAndTendsToOneEighth) {
  for (double z = 1e-3; z < 60; z *= 1.37) {
    const double want = (1.0 / (1.0 + std::exp(-z)) - 0.5) / (2 * z);
    EXPECT_NEAR(JaakkolaLambda(z), want, 1e-12 * want) << z;
    EXPECT_EQ(JaakkolaLambda(-z), JaakkolaLambda(z)) << z;
  }
  EXPECT_EQ(JaakkolaLambda(0.0), 0.125);
  EXPECT_EQ(JaakkolaLambda(-0.0), 0.125);
  // Continuous across the switch to the Taylor series (1e-4) and close to 1/8 - z^2/96 there
  // (the direct formula loses ~1e-12 to cancellation just above the switch).
  for (const double z : {0.99e-4, 1e-4, 1.01e-4, 1e-6, 1e-3}) {
    EXPECT_NEAR(JaakkolaLambda(z), 0.125 - z * z / 96, 1e-11) << z;
  }
  // Decreasing in |z|, like 1 / (4 |z|) for large |z|.
  double prev = JaakkolaLambda(0);
  for (double z = 0.01; z < 100; z += 0.37) {
    EXPECT_LT(JaakkolaLambda(z), prev);
    prev = JaakkolaLambda(z);
  }
  EXPECT_NEAR(JaakkolaLambda(200.0), 1.0 / 800.0, 1e-12);
  EXPECT_TRUE(std::isfinite(JaakkolaLambda(1e308)));
}

TEST(FastBhm, WithBoundInitOneTwoSequentialScansEqualOneScanOfBoth) {
  // z = 1 fixed: each scan adds the same precision and information whatever came before.
  const HingeGridConfig c = TestGrid();
  FastBhmConfig cfg;
  cfg.prior_mean = -0.3;
  const PointSet a = RandomPoints(30, 0, 4, 0, 3, 7), b = RandomPoints(25, 0, 4, 0, 3, 8);
  const PointSet both = testing::Concat(a, b);
  FastBhmLearner seq{HingeGrid(c), cfg}, once{HingeGrid(c), cfg};
  seq.Update(a.xy, a.occupied.data());
  seq.Update(b.xy, b.occupied.data());
  once.Update(both.xy, both.occupied.data());
  ExpectClose(seq.variance(), once.variance(), 1e-12, "variance");
  ExpectClose(seq.mean(), once.mean(), 1e-12, "mean");
  // With z from the prior the bounds of the second scan depend on the first: not linear.
  cfg.bound_init = BoundInit::kPrior;
  FastBhmLearner seq2{HingeGrid(c), cfg}, once2{HingeGrid(c), cfg};
  seq2.Update(a.xy, a.occupied.data());
  seq2.Update(b.xy, b.occupied.data());
  once2.Update(both.xy, both.occupied.data());
  EXPECT_GT((seq2.mean() - once2.mean()).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(FastBhm, ContinuingFromAMapEqualsContinuingTheLearner) {
  const HingeGridConfig c = TestGrid();
  for (const BoundInit init : {BoundInit::kOne, BoundInit::kPrior}) {
    FastBhmConfig cfg;
    cfg.bound_init = init;
    cfg.em_iterations = 2;
    const PointSet a = RandomPoints(30, 0, 4, 0, 3, 9), b = RandomPoints(25, 0, 4, 0, 3, 10);
    FastBhmLearner whole{HingeGrid(c), cfg};
    whole.Update(a.xy, a.occupied.data());
    const HingeMap after_a = whole.ToMap();
    whole.Update(b.xy, b.occupied.data());
    FastBhmLearner copy(after_a, cfg);
    EXPECT_EQ(copy.mean(), after_a.weights().mean);
    EXPECT_EQ(copy.variance(), after_a.weights().variance);
    EXPECT_TRUE(copy.grid().SameFeatures(after_a.grid()));
    copy.Update(b.xy, b.occupied.data());
    EXPECT_EQ(copy.mean(), whole.mean());
    EXPECT_EQ(copy.variance(), whole.variance());
  }
}

TEST(FastBhm, EmptyScanChangesNothingAndOtherKindsCannotBeContinued) {
  const HingeGrid grid(TestGrid());
  FastBhmLearner l(grid, FastBhmConfig{});
  l.Update(Eigen::Matrix2Xd(2, 0), nullptr);
  EXPECT_EQ(l.mean(), Eigen::VectorXd::Zero(48));
  EXPECT_EQ(l.variance(), Eigen::VectorXd::Constant(48, 1e4));
  const HingeMap hilbert = testing::RandomHingeMap(HingeMapKind::kHilbert, grid, 1);
  testing::ExpectErrorContains([&] { FastBhmLearner(hilbert, FastBhmConfig{}); },
                               {"occupancy.fast_bhm", "occupancy.hilbert"});
}

}  // namespace
}  // namespace foresight::occupancy
