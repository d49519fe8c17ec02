// Hinge-feature maps (Hilbert, Fast-BHM, BHM) and grid maps: queries against independent dense
// computations, gradients against finite differences, the prior outside, artifacts.

#include "inference/mapping/hinge_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "core/h5.h"
#include "inference/engine/artifact.h"
#include "inference/mapping/grid_map.h"
#include "inference/mapping/occupancy_map.h"
#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::occupancy {
namespace {

using testing::ExpectErrorContains;

HingeGridConfig MapGrid() { return testing::SmallGrid(5, 4, 6.71, 1.0); }  // 10 x 8 = 80 features

constexpr HingeMapKind kKinds[] = {HingeMapKind::kHilbert, HingeMapKind::kFastBhm,
                                   HingeMapKind::kBhm};

/// Dense covariance of a map's weights (diagonal for Fast-BHM, zero for Hilbert maps).
Eigen::MatrixXd DenseCovariance(const HingeMap& m) {
  const int t = m.grid().size();
  if (m.kind() == HingeMapKind::kBhm) return m.weights().covariance;
  if (m.kind() == HingeMapKind::kFastBhm) return m.weights().variance.asDiagonal();
  return Eigen::MatrixXd::Zero(t, t);
}

TEST(PredictiveProbability, IsTheProbitApproximation) {
  for (const double m : {-3.0, -0.4, 0.0, 1.7}) {
    for (const double v : {0.0, 0.3, 4.0, 100.0}) {
      EXPECT_NEAR(PredictiveProbability(m, v),
                  1.0 / (1.0 + std::exp(-m / std::sqrt(1.0 + M_PI * v / 8.0))), 1e-15);
    }
  }
  EXPECT_EQ(PredictiveProbability(0.0, 123.0), 0.5);
}

/// E[sigmoid(f)], f ~ N(m, v), by Simpson's rule over m +- 12 standard deviations.
double LogisticNormal(double m, double v) {
  if (v == 0) return testing::ReferenceSigmoid(m);
  const int n = 6000;
  const double a = -12, b = 12, h = (b - a) / n, sd = std::sqrt(v);
  double sum = 0;
  for (int i = 0; i <= n; ++i) {
    const double t = a + i * h;
    const double w = i == 0 || i == n ? 1 : (i % 2 ? 4 : 2);
    sum += w * testing::ReferenceSigmoid(m + sd * t) * std::exp(-0.5 * t * t) / std::sqrt(2 * M_PI);
  }
  return sum * h / 3;
}

TEST(PredictiveProbability, IsWithinTwoPercentOfTheLogisticNormalIntegral) {
  EXPECT_NEAR(LogisticNormal(0.8, 1e-12), testing::ReferenceSigmoid(0.8),
              1e-9);  // quadrature sanity
  double worst = 0;
  for (double m = -6; m <= 6; m += 0.25) {
    for (const double v : {0.0, 0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 1e3}) {
      const double err = std::abs(PredictiveProbability(m, v) - LogisticNormal(m, v));
      EXPECT_LT(err, 0.02) << "m " << m << " v " << v;
      worst = std::max(worst, err);
    }
  }
  EXPECT_GT(worst, 1e-3);  // an approximation, not the integral itself
}

class HingeMapKinds : public ::testing::TestWithParam<HingeMapKind> {
 protected:
  HingeMap Map(std::uint64_t seed = 1) const {
    return testing::RandomHingeMap(GetParam(), HingeGrid(MapGrid()), seed, 0.7, 10.0);
  }
  bool bayesian() const { return GetParam() != HingeMapKind::kHilbert; }
};

TEST_P(HingeMapKinds, QueryEqualsTheDenseComputation) {
  const HingeMap map = Map();
  const HingeGridConfig c = MapGrid();
  const Eigen::MatrixXd sigma = DenseCovariance(map);
  MapWorkspace ws = map.MakeWorkspace();
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> ux(-0.5, 5.0), uy(-0.5, 4.0);
  for (int i = 0; i < 300; ++i) {
    const double x = ux(rng), y = uy(rng);
    const Eigen::VectorXd phi = testing::DenseFeatures(c, x, y);
    const double m = phi.dot(map.weights().mean), v = phi.dot(sigma * phi);
    const double want = bayesian() ? PredictiveProbability(m, v) : testing::ReferenceSigmoid(m);
    const QueryResult q = map.Query(x, y, &ws);
    EXPECT_NEAR(q.probability, want, 1e-12);
    EXPECT_NEAR(q.variance, v, 1e-12 * (1 + v));
    EXPECT_NEAR(map.Probability(x, y, &ws), q.probability, 1e-15);
    double lm, lv;
    EXPECT_EQ(map.Latent(x, y, &ws, &lm, &lv), phi.any());
    EXPECT_NEAR(lm, m, 1e-12 * (1 + std::abs(m)));
    EXPECT_NEAR(lv, v, 1e-12 * (1 + v));
  }
}

TEST_P(HingeMapKinds, GradientMatchesCentralFiniteDifferencesOfTheProbability) {
  const HingeMap map = Map(3);
  const HingeGridConfig c = MapGrid();
  MapWorkspace ws = map.MakeWorkspace();
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> ux(0.0, 4.5), uy(0.0, 3.5);
  const double h = 1e-6;
  int checked = 0;
  double largest = 0;
  while (checked < 300) {
    const double x = ux(rng), y = uy(rng);
    if (testing::DistanceToCutoff(c, x, y) < 1e-4) continue;  // features are cut off nearby
    const QueryResult q = map.Query(x, y, &ws);
    const double fd_x = (map.Probability(x + h, y, &ws) - map.Probability(x - h, y, &ws)) / (2 * h);
    const double fd_y = (map.Probability(x, y + h, &ws) - map.Probability(x, y - h, &ws)) / (2 * h);
    EXPECT_NEAR(q.dp_dx, fd_x, 1e-7 + 1e-5 * std::abs(fd_x)) << x << ", " << y;
    EXPECT_NEAR(q.dp_dy, fd_y, 1e-7 + 1e-5 * std::abs(fd_y)) << x << ", " << y;
    largest = std::max({largest, std::abs(fd_x), std::abs(fd_y)});
    ++checked;
  }
  EXPECT_GT(largest, 0.1);  // the gradients tested are not all tiny
}

TEST_P(HingeMapKinds, OutsideTheGridAndAtNaNTheAnswerIsThePrior) {
  const HingeMap map = Map();
  MapWorkspace ws = map.MakeWorkspace();
  const Eigen::Vector4d e = map.Extent();
  EXPECT_EQ(e, Eigen::Vector4d(-1.0, 5.5, -1.0, 4.5));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<double, double>> outside = {
      {e[0] - 1e-9, 2.0}, {e[1] + 1e-9, 2.0}, {2.0, e[2] - 0.01}, {2.0, e[3] + 3}, {100, -100},
      {nan, 1.0},         {1.0, nan},         {HUGE_VAL, 1.0},    {1e11, 1e11}};
  for (const auto& [x, y] : outside) {
    const QueryResult q = map.Query(x, y, &ws);
    EXPECT_EQ(q.probability, testing::ReferenceSigmoid(0.7)) << x << ", " << y;
    EXPECT_EQ(q.variance, bayesian() ? 10.0 : 0.0);
    EXPECT_EQ(q.dp_dx, 0.0);
    EXPECT_EQ(q.dp_dy, 0.0);
    EXPECT_EQ(map.Probability(x, y, &ws), q.probability) << x << ", " << y;
    double lm, lv;
    EXPECT_FALSE(map.Latent(x, y, &ws, &lm, &lv));
    EXPECT_EQ(lm, 0.7);
    EXPECT_EQ(lv, bayesian() ? 10.0 : 0.0);
  }
  // Just inside the extent there are features.
  EXPECT_NE(map.Query(e[0] + 1e-6, 0.0, &ws).probability, testing::ReferenceSigmoid(0.7));
}

TEST_P(HingeMapKinds, BatchQueriesEqualSingleQueries) {
  const HingeMap map = Map();
  MapWorkspace ws = map.MakeWorkspace();
  Eigen::Matrix2Xd pts =
      Eigen::Matrix2Xd::Random(2, 50) * 3.0 + Eigen::Vector2d(2.5, 2.0).replicate(1, 50);
  MapQueryBatch out;
  map.QueryBatch(pts, &ws, &out);
  Eigen::VectorXd p(50);
  map.ProbabilityBatch(pts, &ws, p);
  for (int i = 0; i < 50; ++i) {
    const QueryResult q = map.Query(pts(0, i), pts(1, i), &ws);
    EXPECT_EQ(out.probability[i], q.probability);
    EXPECT_EQ(out.variance[i], q.variance);
    EXPECT_EQ(out.gradient(0, i), q.dp_dx);
    EXPECT_EQ(out.gradient(1, i), q.dp_dy);
    EXPECT_NEAR(p[i], q.probability, 1e-15);  // Probability() squashes in another order
  }
  Eigen::VectorXd wrong(3);
  ExpectErrorContains([&] { map.ProbabilityBatch(pts, &ws, wrong); }, {"3 entries for 50 points"});
}

TEST_P(HingeMapKinds, SaveLoadRoundTripsExactlyInFloat64AndToFloatPrecisionInFloat32) {
  const HingeMap map = Map(5);
  testing::TempDir dir;
  for (const StoredPrecision precision : {StoredPrecision::kFloat64, StoredPrecision::kFloat32}) {
    const std::string path = dir.File(precision == StoredPrecision::kFloat64 ? "f64.h5" : "f32.h5");
    map.Save(path, "model: x\n", 42, precision);
    const HingeMap back = HingeMap::Load(path);
    const Artifact a = Artifact::Open(path, "");
    EXPECT_EQ(a.seed(), 42);
    EXPECT_EQ(a.config_yaml(), "model: x\n");
    EXPECT_EQ(back.kind(), map.kind());
    EXPECT_EQ(back.model_type(), map.model_type());
    EXPECT_TRUE(back.grid().SameFeatures(map.grid()));
    EXPECT_EQ(back.grid().config().x_max, map.grid().config().x_max);
    EXPECT_EQ(back.prior_mean(), 0.7);
    EXPECT_EQ(back.prior_variance(), 10.0);
    const auto round = [precision](const auto& m) -> Eigen::MatrixXd {
      if (precision == StoredPrecision::kFloat64) return m;
      return m.template cast<float>().template cast<double>();
    };
    EXPECT_EQ(back.weights().mean, round(map.weights().mean));
    EXPECT_EQ(back.weights().variance, round(map.weights().variance));
    EXPECT_EQ(back.weights().covariance, round(map.weights().covariance));
    MapWorkspace ws = map.MakeWorkspace();
    for (double x = -0.5; x < 5.0; x += 0.37) {
      for (double y = -0.5; y < 4.0; y += 0.41) {
        const double p0 = map.Probability(x, y, &ws), p1 = back.Probability(x, y, &ws);
        if (precision == StoredPrecision::kFloat64) {
          EXPECT_EQ(p0, p1);
        } else {
          EXPECT_NEAR(p0, p1, 1e-5);
        }
      }
    }
  }
}

TEST_P(HingeMapKinds, LoadOccupancyMapDispatchesOnTheModelType) {
  testing::TempDir dir;
  Map().Save(dir.File("m.h5"), "", 0);
  const auto loaded = LoadMap(dir.File("m.h5"));
  ASSERT_NE(dynamic_cast<const HingeMap*>(loaded.get()), nullptr);
  EXPECT_EQ(loaded->model_type(), ModelType(GetParam()));
  EXPECT_EQ(static_cast<const HingeMap&>(*loaded).kind(), GetParam());
  // Asking for another kind by type is an error naming the file.
  for (const HingeMapKind other : kKinds) {
    if (other == GetParam()) continue;
    ExpectErrorContains([&] { HingeMap::Load(dir.File("m.h5"), ModelType(other)); },
                        {"m.h5", ModelType(GetParam()), ModelType(other)});
  }
}

INSTANTIATE_TEST_SUITE_P(AllKinds, HingeMapKinds, ::testing::ValuesIn(kKinds),
                         [](const auto& param_info) {
                           return std::string(ModelType(param_info.param)).substr(10);
                         });

TEST(HingeMap, BadFilesAreErrorsNamingTheFile) {
  testing::TempDir dir;
  const HingeMap good = testing::RandomHingeMap(HingeMapKind::kFastBhm, HingeGrid(MapGrid()), 1);
  good.Save(dir.File("good.h5"), "", 0);
  std::filesystem::copy_file(dir.File("good.h5"), dir.File("trunc.h5"));
  testing::Truncate(dir.File("trunc.h5"), std::filesystem::file_size(dir.File("good.h5")) / 2);
  ExpectErrorContains([&] { HingeMap::Load(dir.File("trunc.h5")); }, {"trunc.h5"});
  ExpectErrorContains([&] { LoadMap(dir.File("trunc.h5")); }, {"trunc.h5"});
  testing::WriteText(dir.File("notes.h5"), "this is not HDF5\n");
  ExpectErrorContains([&] { HingeMap::Load(dir.File("notes.h5")); }, {"notes.h5"});
  ExpectErrorContains([&] { HingeMap::Load(dir.File("none.h5")); }, {"none.h5", "not found"});
  testing::WriteRandomSpanArtifact(dir.File("span.h5"), testing::RandomSpanSpec{});
  ExpectErrorContains([&] { HingeMap::Load(dir.File("span.h5")); },
                      {"span.h5", "not a hinge-feature occupancy map"});
  ExpectErrorContains([&] { LoadMap(dir.File("span.h5")); }, {"span.h5", "not an occupancy map"});
  const GridMap grid(GridGeometry{0, 0, 0.5, 4, 3}, Eigen::MatrixXf::Constant(3, 4, 0.2f),
                     CellType::kFloat32);
  grid.Save(dir.File("grid.h5"), "", 0);
  ExpectErrorContains([&] { HingeMap::Load(dir.File("grid.h5")); }, {"grid.h5", "occupancy.grid"});
  // A hinge artifact with bad contents: weights of the wrong size, and a negative variance.
  for (const auto& [name, size, variance] :
       {std::tuple{"short.h5", 79, 1.0}, std::tuple{"negative.h5", 80, -1.0}}) {
    {
      h5::File f = h5::File::Create(dir.File(name));
      Artifact::WriteHeader(&f, kFastBhmType, "", 0);
      const auto& c = good.grid().config();
      const std::initializer_list<std::pair<const char*, double>> attrs = {
          {"x_min", c.x_min},
          {"x_max", c.x_max},
          {"y_min", c.y_min},
          {"y_max", c.y_max},
          {"spacing", c.spacing},
          {"gamma", c.gamma},
          {"cutoff_radius", c.cutoff_radius},
          {"prior_mean", 0.0},
          {"prior_variance", 1.0}};
      for (const auto& [k, v] : attrs) f.SetAttr("/model", k, v);
      f.WriteMatrix("/weights/mean", Eigen::VectorXd::Zero(size));
      f.WriteMatrix("/weights/variance", Eigen::VectorXd::Constant(size, variance));
    }
    const std::string bad = dir.File(name);  // clang 14: a lambda cannot capture a binding
    ExpectErrorContains([&] { HingeMap::Load(bad); }, {name});
  }
}

TEST(HingeMap, ConstructorRejectsInconsistentWeights) {
  const HingeGrid grid(MapGrid());
  HingeWeights w;
  w.mean = Eigen::VectorXd::Zero(79);
  ExpectErrorContains([&] { HingeMap(HingeMapKind::kHilbert, grid, w, 0, 1); },
                      {"79 weight means", "80 features"});
  w.mean = Eigen::VectorXd::Zero(80);
  w.mean[3] = std::nan("");
  ExpectErrorContains([&] { HingeMap(HingeMapKind::kHilbert, grid, w, 0, 1); }, {"not finite"});
  w.mean[3] = 0;
  ExpectErrorContains([&] { HingeMap(HingeMapKind::kFastBhm, grid, w, 0, 1); },
                      {"0 weight variances"});
  w.variance = Eigen::VectorXd::Ones(80);
  w.variance[7] = 0;
  ExpectErrorContains([&] { HingeMap(HingeMapKind::kFastBhm, grid, w, 0, 1); }, {"positive"});
  w.variance[7] = 1;
  ExpectErrorContains([&] { HingeMap(HingeMapKind::kFastBhm, grid, w, 0, -1); },
                      {"prior N(0, -1)"});
  ExpectErrorContains([&] { HingeMap(HingeMapKind::kBhm, grid, w, 0, 1); },
                      {"covariance is 0 x 0", "80 x 80"});
}

// ---- grid maps ------------------------------------------------------------------------------

TEST(GridMapCells, EncodeAndDecode) {
  EXPECT_EQ(EncodeCell(0.0f), 0);
  EXPECT_EQ(EncodeCell(1.0f), 254);
  EXPECT_EQ(EncodeCell(0.5f), 127);
  EXPECT_EQ(EncodeCell(-0.3f), 0);
  EXPECT_EQ(EncodeCell(7.0f), 254);
  EXPECT_EQ(EncodeCell(std::nanf("")), 255);
  EXPECT_EQ(EncodeCell(HUGE_VALF), 255);
  EXPECT_EQ(DecodeCell(255), 0.5f);
  for (int q = 0; q < 255; ++q) {
    EXPECT_EQ(DecodeCell(static_cast<std::uint8_t>(q)), q / 254.0f);
    EXPECT_EQ(EncodeCell(DecodeCell(static_cast<std::uint8_t>(q))), q);
  }
  for (float p = 0; p <= 1; p += 0.001f)
    EXPECT_LE(std::abs(DecodeCell(EncodeCell(p)) - p), 0.5f / 254 + 1e-7f);
}

GridMap Asymmetric(CellType type) {
  Eigen::MatrixXf p(3, 4);              // ny = 3 rows, nx = 4 columns; cell (ix, iy) = p(iy, ix)
  p << 0.0f, 0.1f, 0.2f, 0.3f,          //
      0.4f, std::nanf(""), 0.6f, 0.7f,  //
      0.8f, 0.9f, 1.0f, 0.25f;
  return GridMap(GridGeometry{-1.0, 2.0, 0.5, 4, 3}, p, type);
}

TEST(GridMap, QueriesReadTheCellUnderThePoint) {
  const GridMap g = Asymmetric(CellType::kFloat32);
  MapWorkspace ws = g.MakeWorkspace();
  EXPECT_EQ(g.Extent(), Eigen::Vector4d(-1.0, 1.0, 2.0, 3.5));
  EXPECT_FLOAT_EQ(g.Query(-0.75, 2.25, &ws).probability, 0.0f);  // cell (0, 0)
  EXPECT_FLOAT_EQ(g.Query(0.75, 2.25, &ws).probability, 0.3f);   // cell (3, 0)
  EXPECT_FLOAT_EQ(g.Query(-0.75, 3.25, &ws).probability, 0.8f);  // cell (0, 2)
  EXPECT_FLOAT_EQ(g.Query(-0.25, 2.75, &ws).probability, 0.5f);  // unknown cell (1, 1)
  const QueryResult q = g.Query(0.25, 2.75, &ws);                // cell (2, 1)
  EXPECT_FLOAT_EQ(q.probability, 0.6f);
  EXPECT_NEAR(q.dp_dx, (0.7 - 0.5) / 1.0, 1e-6);  // neighbours (3, 1) and unknown (1, 1)
  EXPECT_NEAR(q.dp_dy, (1.0 - 0.2) / 1.0, 1e-6);
  EXPECT_EQ(q.variance, 0.0);
  const QueryResult edge = g.Query(-0.75, 2.25, &ws);  // neighbours outside count as 0.5
  EXPECT_NEAR(edge.dp_dx, (0.1 - 0.5) / 1.0, 1e-6);
  EXPECT_NEAR(edge.dp_dy, (0.4 - 0.5) / 1.0, 1e-6);
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{
           {-1.01, 2.5}, {1.0, 2.5}, {0, 1.99}, {0, 3.5}, {std::nan(""), 2.5}}) {
    const QueryResult o = g.Query(x, y, &ws);
    EXPECT_EQ(o.probability, 0.5);
    EXPECT_EQ(o.dp_dx, 0.0);
    EXPECT_EQ(g.Probability(x, y, &ws), 0.5);
  }
  EXPECT_EQ(g.PayloadBytes(), 48);
  EXPECT_EQ(Asymmetric(CellType::kUint8).PayloadBytes(), 12);
}

TEST(GridMap, RoundTripsAsFloat32ExactlyAndAsUint8Quantised) {
  testing::TempDir dir;
  for (const CellType type : {CellType::kFloat32, CellType::kUint8}) {
    const GridMap g = Asymmetric(type);
    const std::string path = dir.File(type == CellType::kUint8 ? "u8.h5" : "f32.h5");
    g.Save(path, "model: occupancy.grid\n", 3);
    const GridMap back = GridMap::Load(path);
    EXPECT_EQ(back.cell_type(), type);
    EXPECT_EQ(back.geometry().nx, 4);
    EXPECT_EQ(back.geometry().ny, 3);
    EXPECT_EQ(back.geometry().x_min, -1.0);
    EXPECT_EQ(back.geometry().y_min, 2.0);
    EXPECT_EQ(back.geometry().resolution, 0.5);
    // uint8: quantised already in the constructor; unknown cells stay NaN (stored as 255 / NaN).
    for (Eigen::Index i = 0; i < g.cells().size(); ++i) {
      const float a = back.cells().data()[i], b = g.cells().data()[i];
      EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << i;
    }
    const auto loaded = LoadMap(path);
    EXPECT_EQ(loaded->model_type(), kGridMapType);
    ASSERT_NE(dynamic_cast<const GridMap*>(loaded.get()), nullptr);
    const Eigen::MatrixXf& c = back.cells();
    EXPECT_TRUE(std::isnan(c(1, 1)));  // unknown
    MapWorkspace ws0;
    EXPECT_EQ(back.Probability(-1.0 + 1.5 * 0.5, 2.0 + 1.5 * 0.5, &ws0), 0.5);  // answered as 0.5
    const float tol = type == CellType::kUint8 ? 0.5f / 254 : 0.0f;
    EXPECT_NEAR(c(0, 3), 0.3f, tol);
    EXPECT_NEAR(c(2, 3), 0.25f, tol);
    EXPECT_NEAR(c(2, 0), 0.8f, tol);
  }
}

TEST(GridMap, InvalidGridsAreErrors) {
  ExpectErrorContains(
      [] {
        GridMap(GridGeometry{0, 0, 0.5, 4, 3}, Eigen::MatrixXf::Zero(4, 3), CellType::kFloat32);
      },
      {"cells are 4 x 3, expected 3 x 4"});
  ExpectErrorContains(
      [] {
        GridMap(GridGeometry{0, 0, 0.0, 4, 3}, Eigen::MatrixXf::Zero(3, 4), CellType::kFloat32);
      },
      {"invalid geometry"});
  ExpectErrorContains(
      [] {
        GridMap(GridGeometry{0, 0, 0.5, 4, 3}, Eigen::MatrixXf::Constant(3, 4, 1.5f),
                CellType::kFloat32);
      },
      {"1.5 outside [0, 1]"});
  testing::TempDir dir;
  Asymmetric(CellType::kFloat32).Save(dir.File("g.h5"), "", 0);
  testing::WriteRandomSpanArtifact(dir.File("span.h5"), testing::RandomSpanSpec{});
  ExpectErrorContains([&] { GridMap::Load(dir.File("span.h5")); }, {"span.h5", "occupancy.grid"});
  testing::RandomHingeMap(HingeMapKind::kFastBhm, HingeGrid(MapGrid()), 1)
      .Save(dir.File("bhm.h5"), "", 0);
  ExpectErrorContains([&] { GridMap::Load(dir.File("bhm.h5")); }, {"bhm.h5", "occupancy.fast_bhm"});
}

// Fuzz finding (tests/fuzz/corpus/occupancy_artifact/regress_nan_bhm_covariance): a NaN
// off-diagonal covariance entry of a BHM artifact loaded and every query answered NaN.
TEST(HingeMapErrors, NonFiniteBhmCovarianceIsRefused) {
  const HingeMap good = testing::RandomHingeMap(HingeMapKind::kBhm, HingeGrid(MapGrid()), 1);
  HingeWeights w = good.weights();
  w.covariance(3, 2) = std::numeric_limits<double>::quiet_NaN();
  ExpectErrorContains([&] { HingeMap(HingeMapKind::kBhm, HingeGrid(MapGrid()), w, 0.0, 10.0); },
                      {"covariance entry (3, 2)", "nan"});
}

}  // namespace
}  // namespace foresight::occupancy
