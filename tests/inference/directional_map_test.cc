// Kernel features and the directional-map engine against independent computations (torch-free).

#include "inference/directional/directional_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/von_mises.h"
#include "inference/directional/features.h"
#include "inference/prediction/span_predictor.h"
#include "tests/inference/directional_test_util.h"
#include "tests/test_util.h"

namespace foresight::directional {
namespace {

using testing::SmallFeatureConfig;

TEST(DirectionalFeatures, KernelsMatchClosedFormAndCutoff) {
  const FeatureConfig c = SmallFeatureConfig();
  const Features f(c);
  EXPECT_EQ(f.spatial_size(), 20);
  // Inducing points at cell centres, row-major over x then y.
  EXPECT_TRUE(f.SpatialPoint(0).isApprox(Eigen::Vector2d(1.0, -1.0)));
  EXPECT_TRUE(f.SpatialPoint(6).isApprox(Eigen::Vector2d(3.0, 1.0)));
  EXPECT_DOUBLE_EQ(f.TimePoint(0), 0.0);
  EXPECT_DOUBLE_EQ(f.TimePoint(2), 60.0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(-8, 18), uy(-9, 13), ut(-30, 90);
  Eigen::VectorXf phi(f.spatial_size()), phit(f.time_size());
  for (int trial = 0; trial < 300; ++trial) {
    const double x = ux(rng), y = uy(rng), t = ut(rng);
    f.Spatial(x, y, phi);
    for (int j = 0; j < f.spatial_size(); ++j) {
      const double d2 = (Eigen::Vector2d(x, y) - f.SpatialPoint(j)).squaredNorm();
      const double expected = d2 > std::pow(c.cutoff * c.length_scale, 2)
                                  ? 0.0
                                  : std::exp(-d2 / (2 * c.length_scale * c.length_scale));
      EXPECT_NEAR(phi[j], expected, 1e-7) << x << " " << y << " j " << j;
    }
    f.Temporal(t, phit);
    const double tc = std::clamp(t, c.t_min, c.t_max);
    for (int k = 0; k < f.time_size(); ++k)
      EXPECT_NEAR(phit[k], std::exp(-std::pow(tc - f.TimePoint(k), 2) / (2 * 400.0)), 1e-7);
  }
  // One temporal inducing point sits at the middle of the range.
  FeatureConfig one = c;
  one.time_points = 1;
  EXPECT_DOUBLE_EQ(Features(one).TimePoint(0), 30.0);
}

TEST(DirectionalFeatures, ResolveExtentAndBadConfigs) {
  FeatureConfig c = SmallFeatureConfig();
  c.auto_extent = true;
  Eigen::VectorXd x(3), y(3), t(3);
  x << 1, 4, 2;
  y << -1, 0, 5;
  t << 10, 3, 7;
  FeatureConfig r = ResolveExtent(c, x, y, t);
  EXPECT_FALSE(r.auto_extent);
  EXPECT_EQ(r.x_min, 1);
  EXPECT_EQ(r.y_max, 5);
  EXPECT_EQ(r.t_max, 60);  // time range left alone
  c.auto_time_range = true;
  r = ResolveExtent(c, x, y, t);
  EXPECT_EQ(r.t_min, 3);
  EXPECT_EQ(r.t_max, 10);
  FeatureConfig bad = SmallFeatureConfig();
  bad.x_max = bad.x_min;
  testing::ExpectErrorContains([&] { Features{bad}; }, {"empty spatial extent"});
  bad = SmallFeatureConfig();
  bad.length_scale = 0;
  testing::ExpectErrorContains([&] { Features{bad}; }, {"length scales"});
}

/// Independent forward pass: dense features, the sequence phi_s * phi_t[k] through Lstm::Forward,
/// heads by matrix products.
Eigen::VectorXf ReferenceRaw(const Map& m, double x, double y, double t) {
  const Features& f = m.features();
  Eigen::VectorXf phis(f.spatial_size()), phit(f.time_size());
  f.Spatial(x, y, phis);
  f.Temporal(t, phit);
  Eigen::VectorXf z;
  if (m.variant() == Variant::kSpatial) {
    z = phis;
  } else {
    Eigen::MatrixXf seq(f.time_size(), f.spatial_size());
    for (int k = 0; k < f.time_size(); ++k) seq.row(k) = phit[k] * phis.transpose();
    auto ws = m.lstm().MakeWorkspace();
    z = m.lstm().Forward(seq, &ws);
  }
  const Heads& h = m.heads();
  Eigen::VectorXf raw(3 * m.components());
  raw << h.alpha_w * z + h.alpha_b, h.mu_w * z + h.mu_b, h.kappa_w * z + h.kappa_b;
  return raw;
}

class EngineVariants : public ::testing::TestWithParam<Variant> {};

TEST_P(EngineVariants, MatchesDenseReferenceAndIsAProperMixture) {
  const Map m = testing::RandomDirectionalMap(GetParam(), SmallFeatureConfig(), 12, 5, 4);
  auto ws = m.MakeWorkspace();
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> ux(-3, 13), uy(-5, 9), ut(-10, 70);
  for (int trial = 0; trial < 50; ++trial) {
    const double x = ux(rng), y = uy(rng), t = ut(rng);
    m.RawOutput(x, y, t, &ws);
    const Eigen::VectorXf ref = ReferenceRaw(m, x, y, t);
    for (int k = 0; k < ref.size(); ++k)
      EXPECT_NEAR(ws.raw[k], ref[k], 1e-5 * std::max(1.0f, std::abs(ref[k])));
    m.QueryOne(x, y, t, &ws);
    EXPECT_NEAR(ws.alpha.sum(), 1.0, 1e-12);
    EXPECT_TRUE((ws.kappa.array() > 0).all());
    EXPECT_TRUE((ws.kappa.array() <= m.max_kappa() * (1 + 1e-12)).all());
    EXPECT_TRUE((ws.mu.array() >= -M_PI).all() && (ws.mu.array() < M_PI).all());
    // The density integrates to one over the circle (midpoint rule, periodic: spectrally accurate).
    const int n = 4000;
    Eigen::VectorXd xs = Eigen::VectorXd::Constant(n, x), ys = Eigen::VectorXd::Constant(n, y),
                    ts = Eigen::VectorXd::Constant(n, t), th(n), d(n);
    for (int i = 0; i < n; ++i) th[i] = -M_PI + (i + 0.5) * 2 * M_PI / n;
    m.Density(xs, ys, ts, th, &ws, d);
    if (ws.kappa.maxCoeff() < 1e4) {
      EXPECT_NEAR(d.sum() * 2 * M_PI / n, 1.0, 1e-6);
    }
    EXPECT_NEAR(d[17], std::exp(VonMisesMixtureLogDensity(th[17], ws.alpha, ws.mu, ws.kappa)),
                1e-12);
  }
}

TEST_P(EngineVariants, QueriesOutsideTheGridAndTimeRange) {
  const Map m = testing::RandomDirectionalMap(GetParam(), SmallFeatureConfig(), 12, 5, 6);
  auto ws = m.MakeWorkspace();
  // t is clamped to [t_min, t_max] = [0, 60].
  m.QueryOne(4.0, 2.0, 60.0, &ws);
  const Eigen::VectorXd a = ws.alpha, mu = ws.mu;
  m.QueryOne(4.0, 2.0, 1e6, &ws);
  EXPECT_TRUE(ws.alpha.isApprox(a, 1e-12));
  EXPECT_TRUE(ws.mu.isApprox(mu, 1e-12));
  m.QueryOne(4.0, 2.0, -5.0, &ws);
  const Eigen::VectorXd a0 = ws.alpha;
  m.QueryOne(4.0, 2.0, 0.0, &ws);
  EXPECT_TRUE(ws.alpha.isApprox(a0, 1e-12));
  // Far from every inducing point all features are 0: one data-free mixture, finite, everywhere.
  m.QueryOne(1e4, -3e5, 30.0, &ws);
  const Eigen::VectorXd far_alpha = ws.alpha, far_kappa = ws.kappa;
  EXPECT_TRUE(far_alpha.allFinite() && far_kappa.allFinite());
  m.QueryOne(-200.0, 40.0, 30.0, &ws);
  EXPECT_TRUE(ws.alpha.isApprox(far_alpha, 1e-12));
  EXPECT_TRUE(ws.kappa.isApprox(far_kappa, 1e-12));
  m.QueryOne(1e300, -1e300, 30.0, &ws);
  EXPECT_TRUE(ws.alpha.isApprox(far_alpha, 1e-12));
  // Just outside the extent the map is still informed by the nearby inducing points.
  m.QueryOne(10.5, 2.0, 30.0, &ws);
  EXPECT_FALSE(ws.alpha.isApprox(far_alpha, 1e-6));
  // Non-finite queries are errors.
  testing::ExpectErrorContains([&] { m.QueryOne(NAN, 1.0, 2.0, &ws); }, {"not finite"});
  testing::ExpectErrorContains([&] { m.QueryOne(1.0, 1.0, INFINITY, &ws); }, {"not finite"});
  Eigen::VectorXd x(2), y(2), t(2), th(2), d(2);
  x << 1, 2;
  y << 1, 2;
  t << 1, 2;
  th << 0, NAN;
  testing::ExpectErrorContains([&] { m.Density(x, y, t, th, &ws, d); }, {"heading 1"});
  VonMisesMixtureBatch b;
  testing::ExpectErrorContains([&] { m.Query(x, y, t.head(1), &ws, &b); }, {"sizes"});
}

INSTANTIATE_TEST_SUITE_P(Directional, EngineVariants,
                         ::testing::Values(Variant::kSpatiotemporal, Variant::kSpatial),
                         [](const ::testing::TestParamInfo<Variant>& p) {
                           return std::string(VariantName(p.param));
                         });

TEST(DirectionalArtifact, RoundTripAndWrongKinds) {
  testing::TempDir dir;
  for (const Variant v : {Variant::kSpatiotemporal, Variant::kSpatial}) {
    const Map m = testing::RandomDirectionalMap(v, SmallFeatureConfig(), 8, 3, 2, 2.0f, 50.0);
    const std::string path = dir.File(std::string(VariantName(v)) + ".h5");
    m.Save(path, "model: directional\n", 0);
    const Map loaded = Map::Load(path);
    EXPECT_EQ(loaded.variant(), v);
    EXPECT_EQ(loaded.components(), 3);
    EXPECT_NEAR(loaded.max_kappa(), 50.0, 1e-9);
    auto w1 = m.MakeWorkspace(), w2 = loaded.MakeWorkspace();
    m.RawOutput(3.3, 1.1, 20, &w1);
    loaded.RawOutput(3.3, 1.1, 20, &w2);
    EXPECT_TRUE(w1.raw.isApprox(w2.raw));
    // A directional artifact is not a SPAN predictor, and vice versa.
    testing::ExpectErrorContains([&] { span::Predictor::Load(path); },
                                 {path, "'directional_map'", "expected 'span_predictor'"});
  }
  const std::string span = dir.File("span.h5");
  testing::WriteRandomSpanArtifact(span, {});
  testing::ExpectErrorContains([&] { Map::Load(span); },
                               {span, "'span_predictor'", "expected 'directional_map'"});
  testing::ExpectErrorContains([&] { Map::Load(dir.File("missing.h5")); }, {"missing.h5"});
  // Inconsistent tensors: an LSTM that does not take M_s inputs.
  FeatureConfig other = SmallFeatureConfig();
  other.cells_x = 6;
  const Map good = testing::RandomDirectionalMap(Variant::kSpatiotemporal, other, 8, 3, 2);
  // The features of the 5 x 4 grid with the LSTM of the 6 x 4 grid.
  const Map small =
      testing::RandomDirectionalMap(Variant::kSpatiotemporal, SmallFeatureConfig(), 8, 3, 2);
  testing::ExpectErrorContains(
      [&] { Map(Variant::kSpatiotemporal, SmallFeatureConfig(), good.lstm(), small.heads()); },
      {"LSTM takes 24 inputs", "M_s = 20"});
}

}  // namespace
}  // namespace foresight::directional
