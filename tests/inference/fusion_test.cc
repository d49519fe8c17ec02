// Fusion of Fast-BHMs: conflation in closed form, the increment rule (spec/errata.md ch 3) and
// repeated fusion, checked against single maps trained on everything.
//
// Why exact comparisons are possible: with bound_init one and one EM iteration the bound z = 1 is
// fixed, so a scan adds the same precision A_t = 2 lambda(1) sum_n phi_t(x_n)^2 and information
// b_t = sum_n (y_n - 1/2) phi_t(x_n) to every weight whatever came before. In information form
// (P = 1/s2, h = mu / s2), training is addition: P(prior + D) = P0 + A(D), h = h0 + b(D).

#include "inference/mapping/fusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "models/occupancy/fast_bhm.h"
#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::occupancy {
namespace {

using testing::ExpectErrorContains;
using testing::PointSet;

constexpr double kInf = std::numeric_limits<double>::infinity();

HingeGridConfig FusionGrid() { return testing::SmallGrid(4, 3, 6.71, 1.0); }  // 8 x 6 = 48 features

FastBhmConfig Linear() {
  FastBhmConfig cfg;  // bound_init one, one EM iteration: training is linear in information form
  cfg.prior_mean = 0.1;
  cfg.prior_variance = 1e4;
  return cfg;
}

HingeMap Train(const HingeMap* start, const std::vector<PointSet>& scans,
               const FastBhmConfig& cfg = Linear()) {
  FastBhmLearner l =
      start ? FastBhmLearner(*start, cfg) : FastBhmLearner(HingeGrid(FusionGrid()), cfg);
  for (const PointSet& s : scans) l.Update(s.xy, s.occupied.data());
  return l.ToMap();
}

/// Scans in a region of the grid: robots see overlapping but different parts.
std::vector<PointSet> Scans(int count, double x0, double x1, std::uint64_t seed) {
  std::vector<PointSet> out;
  for (int i = 0; i < count; ++i)
    out.push_back(testing::RandomPoints(15, x0, x1, -0.3, 3.0, seed * 100 + i));
  return out;
}

std::vector<PointSet> Join(std::vector<PointSet> a, const std::vector<PointSet>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

/// Expects two Fast-BHMs to agree in information form: precision and information per weight.
void ExpectSamePosterior(const HingeMap& got, const HingeMap& want, double rel) {
  const Eigen::VectorXd pg = got.weights().variance.cwiseInverse(),
                        pw = want.weights().variance.cwiseInverse();
  const Eigen::VectorXd hg = got.weights().mean.cwiseProduct(pg),
                        hw = want.weights().mean.cwiseProduct(pw);
  for (Eigen::Index t = 0; t < pg.size(); ++t) {
    EXPECT_NEAR(pg[t], pw[t], rel * pw[t]) << "precision of weight " << t;
    EXPECT_NEAR(hg[t], hw[t], rel * (std::abs(hw[t]) + pw[t] * 1e-3))
        << "information of weight " << t;
  }
}

TEST(Conflate, EqualsTheClosedFormProductOfGaussians) {
  const HingeGrid grid(FusionGrid());
  const int t_size = grid.size();
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> u(0.1, 5.0);
  FusionOptions options;
  options.variance_threshold = 4.0;
  std::vector<WeightEstimate> estimates(3);
  for (auto& e : estimates) {
    e.mean.resize(t_size);
    e.variance.resize(t_size);
    for (int t = 0; t < t_size; ++t) {
      e.mean[t] = 2 * n01(rng);
      e.variance[t] = u(rng);  // about a fifth at or above the threshold
    }
  }
  estimates[0].variance[3] = 4.0;  // exactly at the threshold: ignored
  estimates[1].variance[3] = kInf;
  estimates[2].variance[3] = 4.5;
  for (auto& e : estimates) e.variance[5] = kInf;  // no information at all: the prior
  const HingeMap fused = Conflate(grid, estimates, options, -0.2, 7.0);
  EXPECT_EQ(fused.kind(), HingeMapKind::kFastBhm);
  EXPECT_EQ(fused.prior_mean(), -0.2);
  EXPECT_EQ(fused.prior_variance(), 7.0);
  int kept = 0, dropped = 0;
  for (int t = 0; t < t_size; ++t) {
    double precision = 0, info = 0;
    for (const auto& e : estimates) {
      if (e.variance[t] >= 4.0) {
        ++dropped;
        continue;
      }
      ++kept;
      precision += 1 / e.variance[t];
      info += e.mean[t] / e.variance[t];
    }
    if (precision == 0) {
      EXPECT_EQ(fused.weights().variance[t], 7.0) << t;
      EXPECT_EQ(fused.weights().mean[t], -0.2) << t;
      continue;
    }
    EXPECT_NEAR(fused.weights().variance[t], 1 / precision, 1e-14 / precision) << t;
    EXPECT_NEAR(fused.weights().mean[t], info / precision, 1e-13 * (1 + std::abs(info / precision)))
        << t;
  }
  EXPECT_GT(kept, 50);
  EXPECT_GT(dropped, 10);
  EXPECT_EQ(fused.weights().variance[3], 7.0);

  // A base map is taken whole, even where its variance is above the threshold.
  HingeWeights bw{
      Eigen::VectorXd::Constant(t_size, 1.5), Eigen::VectorXd::Constant(t_size, 100.0), {}};
  const HingeMap base(HingeMapKind::kFastBhm, grid, bw, -0.2, 7.0);
  const HingeMap with_base = Conflate(grid, estimates, options, -0.2, 7.0, &base);
  EXPECT_DOUBLE_EQ(with_base.weights().variance[5], 100.0);
  EXPECT_DOUBLE_EQ(with_base.weights().mean[5], 1.5);
  const double p3 = 1 / 100.0;  // weight 3: only the base is informative
  EXPECT_DOUBLE_EQ(with_base.weights().variance[3], 1 / p3);
  const double p0 = 1 / 100.0 + (estimates[0].variance[0] < 4 ? 1 / estimates[0].variance[0] : 0) +
                    (estimates[1].variance[0] < 4 ? 1 / estimates[1].variance[0] : 0) +
                    (estimates[2].variance[0] < 4 ? 1 / estimates[2].variance[0] : 0);
  EXPECT_NEAR(with_base.weights().variance[0], 1 / p0, 1e-14);
}

TEST(Conflate, ABaseOfAnotherKindOrGridAndEstimatesOfTheWrongSizeAreErrors) {
  const HingeGrid grid(FusionGrid());
  const HingeMap bhm = testing::RandomHingeMap(HingeMapKind::kBhm, grid, 1);
  const HingeMap hilbert = testing::RandomHingeMap(HingeMapKind::kHilbert, grid, 1);
  ExpectErrorContains([&] { Conflate(grid, {}, FusionOptions{}, 0, 1, &hilbert); },
                      {"base map", "occupancy.hilbert"});
  ExpectErrorContains([&] { Conflate(grid, {}, FusionOptions{}, 0, 1, &bhm); },
                      {"base map", "occupancy.bhm"});
  HingeGridConfig other = FusionGrid();
  other.spacing = 0.6;
  const HingeMap far = testing::RandomHingeMap(HingeMapKind::kFastBhm, HingeGrid(other), 1);
  ExpectErrorContains([&] { Conflate(grid, {}, FusionOptions{}, 0, 1, &far); }, {"grid differs"});
  WeightEstimate small{Eigen::VectorXd::Zero(5), Eigen::VectorXd::Ones(5)};
  ExpectErrorContains([&] { Conflate(grid, {small}, FusionOptions{}, 0, 1); },
                      {"5 weights for a grid of 48"});
}

TEST(IncrementOf, IsWhatACopyLearnedSinceTheGlobalMap) {
  // G = prior + D1; copy = G + D2; fresh = prior + D2. Linear case:
  //   1/s2_copy - 1/s2_G = A(D2) = 1/s2_fresh - 1/s2_0,
  //   mu_copy/s2_copy - mu_G/s2_G = b(D2) = mu_fresh/s2_fresh - mu_0/s2_0,
  // i.e. the increment is the fresh posterior on D2 alone with the prior divided out.
  const FastBhmConfig cfg = Linear();
  const auto d1 = Scans(3, -0.3, 2.5, 1), d2 = Scans(3, 1.0, 4.0, 2);
  const HingeMap g = Train(nullptr, d1);
  const HingeMap copy = Train(&g, d2);
  const HingeMap fresh = Train(nullptr, d2);
  const WeightEstimate inc = IncrementOf(copy, g);
  int informative = 0, untouched = 0;
  for (Eigen::Index t = 0; t < inc.mean.size(); ++t) {
    const double a = 1 / fresh.weights().variance[t] - 1 / cfg.prior_variance;
    const double b =
        fresh.weights().mean[t] / fresh.weights().variance[t] - cfg.prior_mean / cfg.prior_variance;
    if (fresh.weights().variance[t] == cfg.prior_variance) {  // D2 does not touch weight t
      EXPECT_EQ(inc.variance[t], kInf) << t;
      ++untouched;
      continue;
    }
    // The subtraction 1/s2_copy - 1/s2_G loses digits in proportion to 1/s2_copy / A: compare
    // to 1e-9 relative where A is not swamped by the copy's precision, in absolute terms elsewhere.
    const double p_copy = 1 / copy.weights().variance[t];
    const double inc_p = 1 / inc.variance[t], inc_h = inc.mean[t] / inc.variance[t];
    EXPECT_NEAR(inc_p, a, 1e-9 * a + 1e-14 * p_copy) << t;
    EXPECT_NEAR(inc_h, b, 1e-9 * std::abs(b) + 1e-14 * p_copy) << t;
    if (a > 1e-4 * p_copy) {
      EXPECT_NEAR(inc.variance[t], 1 / a, 1e-9 / a) << t;
      EXPECT_NEAR(inc.mean[t], b / a, 1e-9 * std::abs(b / a) + 1e-12) << t;
      ++informative;
    }
  }
  EXPECT_GT(informative, 10);
  EXPECT_GT(untouched, 3);
  // A copy that learned nothing has an empty increment, and merging it returns the global map.
  const WeightEstimate none = IncrementOf(g, g);
  EXPECT_TRUE((none.variance.array() == kInf).all());
  const HingeMap same = FuseMaps({&g}, {"copy"}, FusionOptions{}, &g);
  EXPECT_TRUE(same.weights().mean.isApprox(g.weights().mean, 1e-14));  // via information form
  EXPECT_TRUE(same.weights().variance.isApprox(g.weights().variance, 1e-14));
}

TEST(FuseMaps, RepeatedFusionOfTwoRobotsEqualsTheSingleMapOnEverything) {
  // Global G = prior + D0; robot copies A = G + D1, B = G + D2. Merged: G (x) inc(A) (x) inc(B)
  //   = P0 + A(D0) + A(D1) + A(D2): the single map on D0, D1, D2, shared data D0 counted once.
  // Exact only with no threshold: an increment of variance >= variance_threshold (a weight a robot
  // barely touched) is left out of the merge by design.
  const auto d0 = Scans(2, -0.3, 4.0, 3), d1 = Scans(3, -0.3, 2.0, 4), d2 = Scans(3, 2.0, 4.0, 5);
  const HingeMap g = Train(nullptr, d0);
  const HingeMap a = Train(&g, d1), b = Train(&g, d2);
  const HingeMap single = Train(nullptr, Join(Join(d0, d1), d2));
  FusionOptions exact;
  exact.variance_threshold = kInf;
  const HingeMap fused = FuseMaps({&a, &b}, {"robot A", "robot B"}, exact, &g);
  ExpectSamePosterior(fused, single, 1e-9);

  // Two rounds: the fused map becomes the next global map.
  const auto d3 = Scans(2, -0.3, 2.0, 6), d4 = Scans(2, 2.0, 4.0, 7);
  const HingeMap a2 = Train(&fused, d3), b2 = Train(&fused, d4);
  const HingeMap fused2 = FuseMaps({&a2, &b2}, {"robot A", "robot B"}, exact, &fused);
  ExpectSamePosterior(fused2, Train(nullptr, Join(Join(Join(Join(d0, d1), d2), d3), d4)), 1e-9);

  // With the default threshold (1000) only weights with a barely informed increment differ.
  const HingeMap thresholded = FuseMaps({&a, &b}, {"robot A", "robot B"}, FusionOptions{}, &g);
  const WeightEstimate ia = IncrementOf(a, g), ib = IncrementOf(b, g);
  int differ = 0;
  for (Eigen::Index t = 0; t < ia.mean.size(); ++t) {
    const bool weak = (ia.variance[t] >= 1000 && ia.variance[t] < kInf) ||
                      (ib.variance[t] >= 1000 && ib.variance[t] < kInf);
    if (weak) {
      ++differ;
      EXPECT_NE(thresholded.weights().variance[t], fused.weights().variance[t]) << t;
    } else {
      EXPECT_EQ(thresholded.weights().variance[t], fused.weights().variance[t]) << t;
      EXPECT_EQ(thresholded.weights().mean[t], fused.weights().mean[t]) << t;
    }
  }
  EXPECT_GT(differ, 0);
}

TEST(FuseMaps, FuseOnceIsTheConflationOfTheLocalPosteriors) {
  // Local maps from the prior: A = prior + D1, B = prior + D2. Conflation of both counts the
  // prior twice where both are informative: P = 2 P0 + A(D1) + A(D2); weights that neither
  // touched (variance = prior variance 1e4 >= 1000) are filtered and keep the prior.
  const auto d1 = Scans(3, -0.3, 2.2, 8), d2 = Scans(3, 1.8, 4.0, 9);
  const HingeMap a = Train(nullptr, d1), b = Train(nullptr, d2);
  const HingeMap once = FuseMaps({&a, &b}, {"robot A", "robot B"}, FusionOptions{});
  const HingeMap single = Train(nullptr, Join(d1, d2));
  const FastBhmConfig cfg = Linear();
  const double p0 = 1 / cfg.prior_variance, h0 = cfg.prior_mean / cfg.prior_variance;
  int both = 0;
  for (Eigen::Index t = 0; t < a.weights().mean.size(); ++t) {
    const double sa = a.weights().variance[t], sb = b.weights().variance[t];
    double p = 0, h = 0;
    for (const HingeMap* m : {&a, &b}) {
      const double s2 = m->weights().variance[t];
      if (s2 >= 1000) continue;
      p += 1 / s2;
      h += m->weights().mean[t] / s2;
    }
    if (p == 0) {
      EXPECT_EQ(once.weights().variance[t], cfg.prior_variance);
      EXPECT_EQ(once.weights().mean[t], cfg.prior_mean);
      continue;
    }
    EXPECT_NEAR(once.weights().variance[t], 1 / p, 1e-12 / p);
    EXPECT_NEAR(once.weights().mean[t], h / p, 1e-12 * (1 + std::abs(h / p)));
    if (sa < 1000 && sb < 1000) {  // the single map has the prior once, the conflation twice
      ++both;
      const double ps = 1 / single.weights().variance[t], hs = single.weights().mean[t] * ps;
      EXPECT_NEAR(p, ps + p0, 1e-12 * p);
      EXPECT_NEAR(h, hs + h0, 1e-12 * (std::abs(h) + p));
    }
  }
  EXPECT_GT(both, 5);
}

TEST(FuseMaps, MismatchedMapsAreRefusedNamingThem) {
  const auto d = Scans(1, 0.0, 4.0, 10);
  const HingeMap a = Train(nullptr, d);
  HingeGridConfig coarse = FusionGrid();
  coarse.spacing = 0.6;
  FastBhmConfig cfg = Linear();
  const HingeMap other_grid = [&] {
    FastBhmLearner l(HingeGrid(coarse), cfg);
    l.Update(d[0].xy, d[0].occupied.data());
    return l.ToMap();
  }();
  cfg.prior_variance = 100;
  const HingeMap other_prior = Train(nullptr, d, cfg);
  const HingeMap bhm =
      testing::RandomHingeMap(HingeMapKind::kBhm, HingeGrid(FusionGrid()), 1, 0.1, 1e4);
  const HingeMap hilbert =
      testing::RandomHingeMap(HingeMapKind::kHilbert, HingeGrid(FusionGrid()), 1);
  const FusionOptions o;
  ExpectErrorContains(
      [&] {
        FuseMaps({&a, &other_grid}, {"robot A", "robot B"}, o);
      },
      {"robot B: feature grid", "every 0.6 m", "differs from that of robot A", "every 0.5 m"});
  ExpectErrorContains(
      [&] {
        FuseMaps({&a, &other_prior}, {"robot A", "robot B"}, o);
      },
      {"robot B: weight prior N(0.1, 100)", "robot A N(0.1, 10000)"});
  ExpectErrorContains(
      [&] {
        FuseMaps({&a, &bhm}, {"robot A", "robot B"}, o);
      },
      {"robot B: fusion needs occupancy.fast_bhm", "occupancy.bhm"});
  ExpectErrorContains(
      [&] {
        FuseMaps({&hilbert, &a}, {"robot A", "robot B"}, o);
      },
      {"robot A: fusion needs", "occupancy.hilbert"});
  ExpectErrorContains(
      [&] {
        FuseMaps({&a, &a}, {"robot A", "robot B"}, o, &other_grid);
      },
      {"last global map", "feature grid"});
  ExpectErrorContains(
      [&] {
        FuseMaps({&a, &a}, {"robot A", "robot B"}, o, &other_prior);
      },
      {"last global map", "weight prior"});
  ExpectErrorContains(
      [&] {
        FuseMaps({&a, &a}, {"robot A", "robot B"}, o, &bhm);
      },
      {"last global map", "occupancy.bhm"});
  ExpectErrorContains([&] { FuseMaps({}, {}, o); }, {"no maps"});
  ExpectErrorContains([&] { FuseMaps({&a, &a}, {"robot A"}, o); }, {"1 names for 2 maps"});
  ExpectErrorContains([&] { IncrementOf(a, other_grid); }, {"feature grid"});
  ExpectErrorContains([&] { EstimateOf(bhm); }, {"occupancy.bhm"});
}

}  // namespace
}  // namespace foresight::occupancy
