// Hinge features against a brute-force evaluation over every inducing point.

#include "core/hinge_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

using testing::DenseFeatures;
using testing::ReferenceSize;

HingeGridConfig Small(double spacing, double gamma, double cutoff) {
  HingeGridConfig c;
  c.x_min = -1.3;
  c.x_max = 3.1;
  c.y_min = 0.2;
  c.y_max = 2.9;
  c.spacing = spacing;
  c.gamma = gamma;
  c.cutoff_radius = cutoff;
  return c;
}

/// The features of (x, y) as a map index -> value, checking there are no duplicate indices.
std::map<int, double> Sparse(const HingeGrid& g, double x, double y) {
  std::vector<int> idx(g.max_active());
  std::vector<double> phi(g.max_active());
  const int k = g.Features(x, y, idx.data(), phi.data());
  EXPECT_GE(k, 0);
  EXPECT_LE(k, g.max_active());
  std::map<int, double> out;
  for (int i = 0; i < k; ++i) {
    EXPECT_TRUE(idx[i] >= 0 && idx[i] < g.size()) << idx[i];
    EXPECT_TRUE(out.emplace(idx[i], phi[i]).second) << "duplicate feature " << idx[i];
  }
  return out;
}

class HingeGridBruteForce : public ::testing::TestWithParam<HingeGridConfig> {};

TEST_P(HingeGridBruteForce, FeaturesEqualDirectEvaluationWithinTheCutoffAndNoneBeyond) {
  const HingeGridConfig c = GetParam();
  const HingeGrid g(c);
  ASSERT_EQ(g.size(), ReferenceSize(c));
  for (int t = 0; t < g.size(); ++t) EXPECT_EQ(g.Centre(t), testing::ReferenceCentre(c, t));
  const double x_last = c.x_min + (g.nx() - 1) * c.spacing,
               y_last = c.y_min + (g.ny() - 1) * c.spacing;
  std::mt19937_64 rng(11);
  // Inside, near the edges and outside (beyond the cut-off of the outermost centres).
  std::uniform_real_distribution<double> ux(c.x_min - 1.5 * c.cutoff_radius,
                                            x_last + 1.5 * c.cutoff_radius);
  std::uniform_real_distribution<double> uy(c.y_min - 1.5 * c.cutoff_radius,
                                            y_last + 1.5 * c.cutoff_radius);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < 1500; ++i) points.emplace_back(ux(rng), uy(rng));
  // Exactly on centres and grid corners; just inside and just outside the corner's cut-off.
  for (int t = 0; t < g.size(); t += 7) points.push_back(g.Centre(t));
  points.emplace_back(c.x_min, c.y_min);
  points.emplace_back(x_last, y_last);
  points.emplace_back(c.x_min - c.cutoff_radius * 0.999, c.y_min);
  points.emplace_back(c.x_min - c.cutoff_radius * 1.001, c.y_min);
  int max_seen = 0, with_features = 0, without = 0;
  for (const auto& p : points) {
    const std::map<int, double> got = Sparse(g, p.x(), p.y());
    max_seen = std::max(max_seen, static_cast<int>(got.size()));
    (got.empty() ? without : with_features) += 1;
    const Eigen::VectorXd want = DenseFeatures(c, p.x(), p.y());
    for (int t = 0; t < g.size(); ++t) {
      const Eigen::Vector2d ctr = testing::ReferenceCentre(c, t);
      const double d2 = (p - ctr).squaredNorm(), r2 = c.cutoff_radius * c.cutoff_radius;
      const auto it = got.find(t);
      if (std::abs(d2 - r2) < 1e-12) continue;  // on the circle either answer is fine
      if (d2 < r2) {
        ASSERT_NE(it, got.end()) << "feature " << t << " missing at (" << p.x() << ", " << p.y()
                                 << ")";
        EXPECT_NEAR(it->second, want[t], 1e-14 * want[t] + 1e-300);
        EXPECT_NEAR(it->second, std::exp(-c.gamma * d2), 1e-14);
      } else {
        EXPECT_EQ(it, got.end()) << "feature " << t << " at distance " << std::sqrt(d2)
                                 << " beyond the cut-off";
      }
    }
  }
  EXPECT_LE(max_seen, g.max_active());
  EXPECT_GT(with_features, 100);
  EXPECT_GT(without, 10);
}

INSTANTIATE_TEST_SUITE_P(Configs, HingeGridBruteForce,
                         ::testing::Values(Small(0.5, 6.71, 1.0),    // the thesis setting
                                           Small(0.3, 3.0, 0.75),    // cut-off between grid lines
                                           Small(0.25, 1.0, 1.3),    // many features per point
                                           Small(0.7, 10.0, 0.4),    // cut-off below the spacing
                                           Small(0.5, 6.71, 0.5)));  // cut-off on grid lines

TEST(HingeGrid, IntelExtentHas80By70Features) {
  HingeGridConfig c;  // the defaults are the Intel extent of configs/occupancy/intel.yaml
  c.x_min = -20;
  c.x_max = 20;
  c.y_min = -25;
  c.y_max = 10;
  c.spacing = 0.5;
  const HingeGrid g(c);
  EXPECT_EQ(g.nx(), 80);
  EXPECT_EQ(g.ny(), 70);
  EXPECT_EQ(g.size(), 5600);
  EXPECT_EQ(g.Centre(0), Eigen::Vector2d(-20, -25));
  EXPECT_EQ(g.Centre(5599), Eigen::Vector2d(19.5, 9.5));
  EXPECT_EQ(g.Centre(81), Eigen::Vector2d(-19.5, -24.5));
  // A point well inside touches every centre within 1 m: pi r^2 / s^2 ~ 12.6 -> exactly 13 here.
  EXPECT_EQ(Sparse(g, 0.0, 0.0).size(), 13u);
  EXPECT_GE(g.max_active(), 13);
}

TEST(HingeGrid, NonFiniteOrHugeInputsGiveNoFeatures) {
  const HingeGrid g(Small(0.5, 6.71, 1.0));
  std::vector<int> idx(g.max_active(), -7);
  std::vector<double> phi(g.max_active()), gx(g.max_active()), gy(g.max_active());
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<double, double>> bad = {
      {nan, 1.0}, {1.0, nan},  {nan, nan},   {inf, 1.0},   {1.0, -inf},   {-inf, inf},
      {1e300, 1}, {1, -1e300}, {1e12, 1.0},  {-1e11, 1.0}, {1.0, 1e11},   {1.0, -5e9},
      {3e9, 3e9}, {-3e9, 1},   {1e15, 1e15}, {1.0, 1e200}, {-1e20, -1e20}};
  for (const auto& [x, y] : bad) {
    EXPECT_EQ(g.Features(x, y, idx.data(), phi.data()), 0) << x << ", " << y;
    EXPECT_EQ(g.FeaturesWithGradient(x, y, idx.data(), phi.data(), gx.data(), gy.data()), 0)
        << x << ", " << y;
  }
  EXPECT_EQ(idx[0], -7);  // nothing written
}

TEST(HingeGrid, InvalidConfigsThrowNamingTheValues) {
  using testing::ExpectErrorContains;
  auto with = [](auto edit) {
    HingeGridConfig c = Small(0.5, 6.71, 1.0);
    edit(c);
    return c;
  };
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.x_max = c.x_min; })); },
                      {"x range", "-1.3"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.x_max = -5; })); }, {"x range", "-5"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.y_min = std::nan(""); })); },
                      {"y range", "nan"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.y_max = HUGE_VAL; })); },
                      {"y range", "inf"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.spacing = 0; })); }, {"spacing 0"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.spacing = std::nan(""); })); },
                      {"spacing nan"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.gamma = -1; })); }, {"gamma -1"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.cutoff_radius = 0; })); },
                      {"cutoff_radius 0"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.spacing = 1e-4; })); }, {"too many"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.cutoff_radius = 20; })); },
                      {"cutoff_radius 20", "spacing 0.5"});
  // A cut-off so large that window arithmetic in int would overflow.
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.cutoff_radius = 1e10; })); },
                      {"cutoff_radius 1e+10"});
  ExpectErrorContains([&] { HingeGrid(with([](auto& c) { c.cutoff_radius = HUGE_VAL; })); },
                      {"cutoff_radius inf"});
  // A one-point axis is allowed (x range shorter than the spacing rounds to one point).
  const HingeGrid thin(with([](auto& c) { c.x_max = c.x_min + 0.1; }));
  EXPECT_EQ(thin.nx(), 1);
}

TEST(HingeGrid, GradientsMatchCentralFiniteDifferences) {
  const HingeGridConfig c = Small(0.3, 4.0, 0.8);
  const HingeGrid g(c);
  std::vector<int> idx(g.max_active()), idx2(g.max_active());
  std::vector<double> phi(g.max_active()), phi2(g.max_active()), gx(g.max_active()),
      gy(g.max_active());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> ux(c.x_min - 0.5, c.x_max + 0.2),
      uy(c.y_min - 0.5, c.y_max + 0.2);
  const double h = 1e-6;
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double x = ux(rng), y = uy(rng);
    if (testing::DistanceToCutoff(c, x, y) < 1e-4) continue;  // a feature switches on within h
    const int k = g.FeaturesWithGradient(x, y, idx.data(), phi.data(), gx.data(), gy.data());
    // Same features as the plain call.
    ASSERT_EQ(g.Features(x, y, idx2.data(), phi2.data()), k);
    for (int i = 0; i < k; ++i) {
      EXPECT_EQ(idx[i], idx2[i]);
      EXPECT_EQ(phi[i], phi2[i]);
    }
    const auto px = Sparse(g, x + h, y), mx = Sparse(g, x - h, y), py = Sparse(g, x, y + h),
               my = Sparse(g, x, y - h);
    for (int i = 0; i < k; ++i) {
      const double fd_x = (px.at(idx[i]) - mx.at(idx[i])) / (2 * h);
      const double fd_y = (py.at(idx[i]) - my.at(idx[i])) / (2 * h);
      EXPECT_NEAR(gx[i], fd_x, 1e-8 + 1e-6 * std::abs(fd_x));
      EXPECT_NEAR(gy[i], fd_y, 1e-8 + 1e-6 * std::abs(fd_y));
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(HingeGrid, SameFeaturesAndDescribe) {
  const HingeGrid a(Small(0.5, 6.71, 1.0));
  EXPECT_TRUE(a.SameFeatures(HingeGrid(Small(0.5, 6.71, 1.0))));
  EXPECT_FALSE(a.SameFeatures(HingeGrid(Small(0.6, 6.71, 1.0))));
  EXPECT_FALSE(a.SameFeatures(HingeGrid(Small(0.5, 6.0, 1.0))));
  EXPECT_FALSE(a.SameFeatures(HingeGrid(Small(0.5, 6.71, 1.1))));
  HingeGridConfig shifted = Small(0.5, 6.71, 1.0);
  shifted.x_min += 0.25;
  shifted.x_max += 0.25;
  EXPECT_FALSE(a.SameFeatures(HingeGrid(shifted)));
  EXPECT_NE(a.Describe().find("9 x 5 inducing points"), std::string::npos) << a.Describe();
}

}  // namespace
}  // namespace foresight
