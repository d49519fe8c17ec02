#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/von_mises.h"
#include "models/directional/directional_grid_map.h"
#include "tests/alloc_counter.h"  // replaces operator new: one per binary
#include "tests/test_util.h"

namespace foresight::directional {
namespace {

/// n samples uniform in the box [x0, x1] x [y0, y1] with headings from the mixture (alpha, mu,
/// kappa).
void AddSamples(int n, double x0, double x1, double y0, double y1, const std::vector<double>& alpha,
                const std::vector<double>& mu, const std::vector<double>& kappa,
                std::mt19937_64* rng, std::vector<std::array<double, 3>>* out) {
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < n; ++i) {
    double pick = u(*rng);
    std::size_t k = 0;
    while (k + 1 < alpha.size() && pick >= alpha[k]) pick -= alpha[k++];
    out->push_back(
        {x0 + (x1 - x0) * u(*rng), y0 + (y1 - y0) * u(*rng), SampleVonMises(mu[k], kappa[k], rng)});
  }
}

DirectionalSamples ToSamples(const std::vector<std::array<double, 3>>& rows) {
  DirectionalSamples s;
  const auto n = static_cast<Eigen::Index>(rows.size());
  s.x.resize(n);
  s.y.resize(n);
  s.t = Eigen::VectorXd::Zero(n);
  s.theta.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s.x[i] = rows[static_cast<std::size_t>(i)][0];
    s.y[i] = rows[static_cast<std::size_t>(i)][1];
    s.theta[i] = rows[static_cast<std::size_t>(i)][2];
  }
  return s;
}

GridConfig TwoByTwo(GridKind kind) {
  GridConfig c;
  c.kind = kind;
  c.cells_x = 2;
  c.cells_y = 2;
  c.extent = Eigen::Vector4d(0, 2, 0, 4);  // cells 1 m wide, 2 m high
  c.components = 3;
  c.seed = 7;
  return c;
}

TEST(DirectionalGridMap, CellLayoutIsRowMajorOverXThenY) {
  DirectionalSamples s = ToSamples({{0.5, 0.5, 0.0}});
  const GridMap map = GridMap::Fit(s, TwoByTwo(GridKind::kUnimodal));
  EXPECT_EQ(map.num_cells(), 4);
  EXPECT_EQ(map.CellIndex(0.5, 1.0), 0);
  EXPECT_EQ(map.CellIndex(1.5, 1.0), 1);
  EXPECT_EQ(map.CellIndex(0.5, 3.0), 2);
  EXPECT_EQ(map.CellIndex(1.5, 3.0), 3);
  EXPECT_EQ(map.CellIndex(-10, 100), 2);  // outside: nearest cell
  EXPECT_TRUE(map.CellCentre(3).isApprox(Eigen::Vector2d(1.5, 3.0)));
  EXPECT_EQ(map.cell_counts(), (std::vector<int>{1, 0, 0, 0}));
  EXPECT_EQ(map.output_components(), 1);
}

TEST(DirectionalGridMap, UnimodalRecoversEachCellAndEmptyCellsAreUniform) {
  std::mt19937_64 rng(1);
  std::vector<std::array<double, 3>> rows;
  const double mus[3] = {0.3, 3.0, -1.7}, kappas[3] = {2.0, 10.0, 40.0};
  AddSamples(4000, 0, 1, 0, 2, {1.0}, {mus[0]}, {kappas[0]}, &rng, &rows);  // cell 0
  AddSamples(4000, 1, 2, 0, 2, {1.0}, {mus[1]}, {kappas[1]}, &rng, &rows);  // cell 1
  AddSamples(4000, 0, 1, 2, 4, {1.0}, {mus[2]}, {kappas[2]}, &rng, &rows);  // cell 2; cell 3 empty
  const GridMap map = GridMap::Fit(ToSamples(rows), TwoByTwo(GridKind::kUnimodal));
  Eigen::VectorXd qx(5), qy(5);
  qx << 0.5, 1.5, 0.5, 1.5, 7.0;
  qy << 1.0, 1.0, 3.0, 3.0, -5.0;  // the last one is outside: nearest cell is cell 1
  VonMisesMixtureBatch out;
  map.Query(qx, qy, &out);
  ASSERT_EQ(out.alpha.rows(), 5);
  ASSERT_EQ(out.alpha.cols(), 1);
  for (int cell = 0; cell < 3; ++cell) {
    EXPECT_EQ(out.alpha(cell, 0), 1.0);
    EXPECT_NEAR(WrapAngle(out.mu(cell, 0) - mus[cell]), 0.0, 4 / std::sqrt(kappas[cell] * 4000))
        << cell;
    EXPECT_NEAR(out.kappa(cell, 0), kappas[cell], 0.08 * kappas[cell]) << cell;
  }
  EXPECT_EQ(out.alpha(3, 0), 1.0);
  EXPECT_EQ(out.kappa(3, 0), 0.0);
  Eigen::VectorXd theta = Eigen::VectorXd::Constant(5, 1.0);
  VonMisesMixtureBatch uniform;
  uniform.Resize(1, 1);
  uniform.alpha << out.alpha(3, 0);
  uniform.mu << out.mu(3, 0);
  uniform.kappa << out.kappa(3, 0);
  EXPECT_NEAR(AverageLikelihood(uniform, theta.head(1)), 1 / (2 * M_PI), 1e-15);
  EXPECT_EQ(out.mu(4, 0), out.mu(1, 0));
  EXPECT_EQ(out.kappa(4, 0), out.kappa(1, 0));
  // Same as FitVonMises on the cell's samples (an independent path to the ML estimate).
  std::vector<double> cell1;
  for (const auto& r : rows)
    if (r[0] >= 1 && r[1] < 2) cell1.push_back(r[2]);
  const VonMisesFit ref = FitVonMises(
      Eigen::Map<Eigen::VectorXd>(cell1.data(), static_cast<Eigen::Index>(cell1.size())),
      Eigen::VectorXd::Ones(static_cast<Eigen::Index>(cell1.size())));
  EXPECT_NEAR(out.mu(1, 0), ref.mu, 1e-12);
  EXPECT_NEAR(out.kappa(1, 0), ref.kappa, 1e-9);
}

TEST(DirectionalGridMap, KappaIsCappedWhenHeadingsCoincide) {
  GridConfig c = TwoByTwo(GridKind::kUnimodal);
  c.max_kappa = 30;
  const GridMap map =
      GridMap::Fit(ToSamples({{0.5, 0.5, 1.0}, {0.6, 0.5, 1.0}, {0.7, 0.5, 1.0}}), c);
  EXPECT_EQ(map.cells().kappa(0, 0), 30.0);
  EXPECT_NEAR(map.cells().mu(0, 0), 1.0, 1e-12);
}

TEST(DirectionalGridMap, MultimodalRecoversABimodalCellAndBeatsUnimodalOnAl) {
  std::mt19937_64 rng(2);
  std::vector<std::array<double, 3>> train_rows, test_rows;
  const std::vector<double> alpha = {0.3, 0.7}, mu = {-2.0, 1.0}, kappa = {20.0, 8.0};
  AddSamples(3000, 0, 1, 0, 2, alpha, mu, kappa, &rng, &train_rows);
  AddSamples(3000, 1, 2, 0, 2, {1.0}, {2.5}, {5.0}, &rng, &train_rows);  // unimodal neighbour
  AddSamples(2000, 0, 1, 0, 2, alpha, mu, kappa, &rng, &test_rows);
  const DirectionalSamples train = ToSamples(train_rows), test = ToSamples(test_rows);

  const GridMap mm = GridMap::Fit(train, TwoByTwo(GridKind::kMultimodal));
  const GridMap um = GridMap::Fit(train, TwoByTwo(GridKind::kUnimodal));
  ASSERT_EQ(mm.output_components(), 3);
  // BIC picks two components in the bimodal cell, one in the unimodal cell.
  const auto& cells = mm.cells();
  int active = 0;
  for (int k = 0; k < 3; ++k) active += cells.alpha(0, k) > 0;
  EXPECT_EQ(active, 2);
  EXPECT_EQ((cells.alpha.row(1).array() > 0).count(), 1);
  EXPECT_NEAR(cells.alpha.row(0).sum(), 1.0, 1e-12);
  for (int j = 0; j < 2; ++j) {
    int k = 0;  // the fitted component nearest the true mean
    for (int m = 1; m < 3; ++m)
      if (cells.alpha(0, m) > 0 &&
          std::abs(WrapAngle(cells.mu(0, m) - mu[static_cast<std::size_t>(j)])) <
              std::abs(WrapAngle(cells.mu(0, k) - mu[static_cast<std::size_t>(j)])))
        k = m;
    EXPECT_NEAR(WrapAngle(cells.mu(0, k) - mu[static_cast<std::size_t>(j)]), 0.0, 0.05) << j;
    EXPECT_NEAR(cells.alpha(0, k), alpha[static_cast<std::size_t>(j)], 0.03) << j;
    EXPECT_NEAR(cells.kappa(0, k), kappa[static_cast<std::size_t>(j)],
                0.15 * kappa[static_cast<std::size_t>(j)])
        << j;
  }
  VonMisesMixtureBatch out_mm, out_um;
  mm.Query(test.x, test.y, &out_mm);
  um.Query(test.x, test.y, &out_um);
  const double al_mm = AverageLikelihood(out_mm, test.theta),
               al_um = AverageLikelihood(out_um, test.theta);
  // True mixture's AL for reference: MM should be close to it, UM well below.
  VonMisesMixtureBatch truth;
  truth.Resize(test.size(), 2);
  for (Eigen::Index i = 0; i < test.size(); ++i) {
    truth.alpha.row(i) << alpha[0], alpha[1];
    truth.mu.row(i) << mu[0], mu[1];
    truth.kappa.row(i) << kappa[0], kappa[1];
  }
  const double al_true = AverageLikelihood(truth, test.theta);
  EXPECT_GT(al_mm, 1.5 * al_um);
  EXPECT_NEAR(al_mm, al_true, 0.03 * al_true);
  EXPECT_LT(MinimumRotationError(out_mm, test.theta), MinimumRotationError(out_um, test.theta));
  // The k-means + BIC initialisation finds the same two modes; it is seeded.
  GridConfig bic = TwoByTwo(GridKind::kMultimodal);
  bic.mixture_init = GridMixtureInit::kKMeansBic;
  const GridMap mm_bic = GridMap::Fit(train, bic);
  EXPECT_EQ((mm_bic.cells().alpha.row(0).array() > 0).count(), 2);
  VonMisesMixtureBatch out_bic;
  mm_bic.Query(test.x, test.y, &out_bic);
  EXPECT_NEAR(AverageLikelihood(out_bic, test.theta), al_mm, 0.01 * al_mm);
  const GridMap again = GridMap::Fit(train, bic);
  EXPECT_EQ(again.cells().mu, mm_bic.cells().mu);
  EXPECT_EQ(again.cells().kappa, mm_bic.cells().kappa);
}

TEST(DirectionalGridMap, DbscanCountsModesAndKMeansRulesAreSelectable) {
  // One cell: clumps of 10 headings at -2.5 and 0.5 and of 6 at 2.0 (spread 0.02 rad), plus 4
  // isolated headings (fewer than min_samples = 5 within eps of each other): noise.
  std::vector<std::array<double, 3>> rows;
  for (int i = 0; i < 10; ++i) rows.push_back({0.5, 0.5, -2.5 + 0.002 * i});
  for (int i = 0; i < 10; ++i) rows.push_back({0.5, 0.5, 0.5 + 0.002 * i});
  for (int i = 0; i < 6; ++i) rows.push_back({0.5, 0.5, 2.0 + 0.004 * i});
  for (double t : {-1.2, -0.4, 1.3, 3.0}) rows.push_back({0.5, 0.5, t});
  const DirectionalSamples s = ToSamples(rows);
  GridConfig c = TwoByTwo(GridKind::kMultimodal);
  c.components = 5;
  auto active = [](const GridMap& m) { return (m.cells().alpha.row(0).array() > 0).count(); };
  EXPECT_EQ(active(GridMap::Fit(s, c)), 3);
  c.components = 2;  // keeps the two largest clusters
  const GridMap two = GridMap::Fit(s, c);
  EXPECT_EQ(active(two), 2);
  c.components = 5;
  c.dbscan_min_samples = 7;  // the clump of 6 becomes noise
  EXPECT_EQ(active(GridMap::Fit(s, c)), 2);
  c.dbscan_min_samples = 50;  // everything is noise: one component from all headings
  EXPECT_EQ(active(GridMap::Fit(s, c)), 1);
  c.dbscan_min_samples = 5;
  c.mixture_init = GridMixtureInit::kKMeansFixed;
  EXPECT_EQ(active(GridMap::Fit(s, c)), 5);
  c.mixture_init = GridMixtureInit::kKMeansBic;
  const auto bic = active(GridMap::Fit(s, c));
  EXPECT_GE(bic, 3);
  EXPECT_LE(bic, 5);
}

TEST(DirectionalGridMap, DenseBlendsNearbyDiscsWithRbfWeights) {
  // 3 x 3 cells of 1 m: disc radius 1 m; each cell trains on every point within 1 m of its centre.
  std::mt19937_64 rng(4);
  std::vector<std::array<double, 3>> rows;
  for (int cell = 0; cell < 9; ++cell) {
    if (cell == 8) continue;  // cell (2, 2) has no points of its own
    const double x0 = cell % 3, y0 = cell / 3;
    AddSamples(200, x0, x0 + 1, y0, y0 + 1, {1.0}, {-3.0 + 0.7 * cell}, {4.0 + cell}, &rng, &rows);
  }
  const DirectionalSamples train = ToSamples(rows);
  GridConfig c;
  c.kind = GridKind::kUnimodal;
  c.cells_x = c.cells_y = 3;
  c.extent = Eigen::Vector4d(0, 3, 0, 3);
  c.dense = true;
  c.length_scale = 0.7;
  const GridMap map = GridMap::Fit(train, c);
  EXPECT_EQ(map.output_components(), 9);

  // Independent reference: each disc's ML fit from the raw points, then the blending rule.
  auto disc_fit = [&](int cell) {
    const Eigen::Vector2d centre(cell % 3 + 0.5, cell / 3 + 0.5);
    std::vector<double> th;
    for (const auto& r : rows)
      if (std::hypot(r[0] - centre.x(), r[1] - centre.y()) <= 1.0) th.push_back(r[2]);
    const VonMisesFit f =
        FitVonMises(Eigen::Map<Eigen::VectorXd>(th.data(), static_cast<Eigen::Index>(th.size())),
                    Eigen::VectorXd::Ones(static_cast<Eigen::Index>(th.size())));
    return std::make_pair(f, static_cast<int>(th.size()));
  };
  Eigen::VectorXd qx(3), qy(3);
  qx << 1.3, 2.9, -4.0;
  qy << 1.6, 2.9, 0.2;  // (-4, 0.2) is clamped to (0, 0.2)
  VonMisesMixtureBatch out;
  map.Query(qx, qy, &out);
  ASSERT_EQ(out.alpha.cols(), 9);
  const Eigen::VectorXd theta = Eigen::VectorXd::LinSpaced(3, -1.0, 2.0);
  for (Eigen::Index i = 0; i < 3; ++i) {
    const double px = std::clamp(qx[i], 0.0, 3.0), py = std::clamp(qy[i], 0.0, 3.0);
    double total = 0;
    std::vector<std::pair<double, VonMisesFit>> parts;
    for (int cell = 0; cell < 9; ++cell) {
      const double d2 = std::pow(px - (cell % 3 + 0.5), 2) + std::pow(py - (cell / 3 + 0.5), 2);
      const auto [fit, count] = disc_fit(cell);
      if (d2 > 1.0 || count == 0) continue;
      const double w = std::exp(-d2 / (2 * 0.7 * 0.7));
      parts.emplace_back(w, fit);
      total += w;
    }
    EXPECT_NEAR(out.alpha.row(i).sum(), 1.0, 1e-12) << i;
    EXPECT_EQ((out.alpha.row(i).array() > 0).count(), static_cast<Eigen::Index>(parts.size())) << i;
    // Compare the densities at a few headings (column order is an implementation detail).
    for (Eigen::Index j = 0; j < theta.size(); ++j) {
      double ref = 0;
      for (const auto& [w, f] : parts)
        ref += w / total * std::exp(VonMisesLogDensity(theta[j], f.mu, f.kappa));
      const double got = std::exp(VonMisesMixtureLogDensity(theta[j], out.alpha.row(i).transpose(),
                                                            out.mu.row(i).transpose(),
                                                            out.kappa.row(i).transpose()));
      EXPECT_NEAR(got, ref, 1e-10 * ref) << i << " " << j;
    }
  }
  // Cell 8 has no points of its own but its disc reaches into its neighbours: not empty.
  EXPECT_GT(map.cell_counts()[8], 0);
}

TEST(DirectionalGridMap, DenseAnswersUniformFarFromData) {
  GridConfig c;
  c.cells_x = c.cells_y = 5;
  c.extent = Eigen::Vector4d(0, 5, 0, 5);
  c.dense = true;
  c.kind = GridKind::kMultimodal;
  c.components = 2;
  const GridMap map = GridMap::Fit(ToSamples({{0.5, 0.5, 1.0}, {0.6, 0.4, 1.2}}), c);
  Eigen::VectorXd qx(2), qy(2);
  qx << 4.5, 0.5;
  qy << 4.5, 0.5;
  VonMisesMixtureBatch out;
  map.Query(qx, qy, &out);
  ASSERT_EQ(out.alpha.cols(), 18);
  EXPECT_EQ(out.alpha(0, 0), 1.0);
  EXPECT_EQ(out.alpha.row(0).sum(), 1.0);
  EXPECT_EQ(out.kappa.row(0).sum(), 0.0);
  EXPECT_NEAR(out.alpha.row(1).sum(), 1.0, 1e-12);
}

TEST(DirectionalGridMap, QueryDoesNotAllocateWhenOutIsSized) {
  std::mt19937_64 rng(8);
  std::vector<std::array<double, 3>> rows;
  AddSamples(500, 0, 4, 0, 4, {0.5, 0.5}, {0.0, 2.0}, {5.0, 5.0}, &rng, &rows);
  Eigen::VectorXd qx = Eigen::VectorXd::LinSpaced(300, -1, 5),
                  qy = Eigen::VectorXd::LinSpaced(300, 5, -1);
  for (bool dense : {false, true}) {
    GridConfig c;
    c.kind = GridKind::kMultimodal;
    c.cells_x = c.cells_y = 4;
    c.extent = Eigen::Vector4d(0, 4, 0, 4);
    c.dense = dense;
    const GridMap map = GridMap::Fit(ToSamples(rows), c);
    VonMisesMixtureBatch out;
    map.Query(qx, qy, &out);
    const double* alpha = out.alpha.data();
    const double* kappa = out.kappa.data();
    g_allocations = 0;
    g_counting = true;
    map.Query(qx, qy, &out);
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << dense;
    EXPECT_EQ(out.alpha.data(), alpha) << dense;  // Eigen storage not reallocated
    EXPECT_EQ(out.kappa.data(), kappa) << dense;
  }
}

TEST(DirectionalGridMap, BadInputIsAnError) {
  const DirectionalSamples s = ToSamples({{0.5, 0.5, 0.0}});
  GridConfig c = TwoByTwo(GridKind::kUnimodal);
  c.cells_x = 0;
  testing::ExpectErrorContains([&] { GridMap::Fit(s, c); }, {"cells_x 0"});
  c = TwoByTwo(GridKind::kUnimodal);
  c.extent = Eigen::Vector4d(0, 0, 0, 1);
  testing::ExpectErrorContains([&] { GridMap::Fit(s, c); }, {"extent", "(0, 0, 0, 1)"});
  c = TwoByTwo(GridKind::kUnimodal);
  c.length_scale = 0;
  testing::ExpectErrorContains([&] { GridMap::Fit(s, c); }, {"length_scale 0"});
  c = TwoByTwo(GridKind::kMultimodal);
  c.components = 0;
  testing::ExpectErrorContains([&] { GridMap::Fit(s, c); }, {"components 0"});
  testing::ExpectErrorContains(
      [&] { GridMap::Fit(DirectionalSamples(), TwoByTwo(GridKind::kUnimodal)); },
      {"training data", "no direction samples"});
  DirectionalSamples nan = s;
  nan.x[0] = std::nan("");
  testing::ExpectErrorContains([&] { GridMap::Fit(nan, TwoByTwo(GridKind::kUnimodal)); },
                               {"training data", "not finite"});
  const GridMap map = GridMap::Fit(s, TwoByTwo(GridKind::kUnimodal));
  VonMisesMixtureBatch out;
  Eigen::VectorXd x(2), y(1);
  x << 0.5, std::nan("");
  y << 0.5;
  testing::ExpectErrorContains([&] { map.Query(x, y, &out); }, {"x [2]", "y [1]"});
  Eigen::VectorXd y2(2);
  y2 << 0.5, 0.5;
  testing::ExpectErrorContains([&] { map.Query(x, y2, &out); }, {"point 1", "not finite"});
}

}  // namespace
}  // namespace foresight::directional
