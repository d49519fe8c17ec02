// Log-odds occupancy grid: the ray traversal against brute force, and the sensor-model updates.

#include "models/occupancy/grid_builder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "tests/test_util.h"

namespace foresight::occupancy {
namespace {

using Cell = std::pair<int, int>;

/// Cells whose interior the segment crosses with positive length (slab test on every cell of the
/// bounding box), plus the cells of both end points. `ambiguous` receives cells crossed by less
/// than 1e-7 (either answer is fine there).
std::set<Cell> ExactCells(double x0, double y0, double x1, double y1, std::set<Cell>* ambiguous) {
  std::set<Cell> out{{int(std::floor(x0)), int(std::floor(y0))},
                     {int(std::floor(x1)), int(std::floor(y1))}};
  const double dx = x1 - x0, dy = y1 - y0;
  const auto interval = [](double a0, double d, int lo, double* t0, double* t1) {
    if (d == 0) {
      const bool in = a0 >= lo && a0 < lo + 1;
      *t0 = in ? -1e300 : 1;
      *t1 = in ? 1e300 : 0;
      return;
    }
    const double ta = (lo - a0) / d, tb = (lo + 1 - a0) / d;
    *t0 = std::min(ta, tb);
    *t1 = std::max(ta, tb);
  };
  const double len = std::hypot(dx, dy);
  for (int i = int(std::floor(std::min(x0, x1))) - 1; i <= int(std::floor(std::max(x0, x1))) + 1;
       ++i) {
    for (int j = int(std::floor(std::min(y0, y1))) - 1; j <= int(std::floor(std::max(y0, y1))) + 1;
         ++j) {
      double ax, bx, ay, by;
      interval(x0, dx, i, &ax, &bx);
      interval(y0, dy, j, &ay, &by);
      const double t0 = std::max({0.0, ax, ay}), t1 = std::min({1.0, bx, by});
      const double crossed = (t1 - t0) * len;
      if (crossed > 1e-7)
        out.insert({i, j});
      else if (crossed > -1e-7 && ambiguous)
        ambiguous->insert({i, j});
    }
  }
  return out;
}

TEST(TraverseCells, VisitsExactlyTheCellsTheSegmentCrossesEndingWithTheEndCell) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-12.0, 12.0);
  std::vector<Cell> cells;
  for (int trial = 0; trial < 2000; ++trial) {
    double x0 = u(rng), y0 = u(rng), x1 = u(rng), y1 = u(rng);
    if (trial % 10 == 1) x1 = x0;  // vertical
    if (trial % 10 == 2) y1 = y0;  // horizontal
    if (trial % 10 == 3) {         // very short
      x1 = x0 + 0.3 * (u(rng) / 12);
      y1 = y0 + 0.3 * (u(rng) / 12);
    }
    TraverseCells(x0, y0, x1, y1, &cells);
    ASSERT_FALSE(cells.empty());
    EXPECT_EQ(cells.front(), Cell(int(std::floor(x0)), int(std::floor(y0))));
    EXPECT_EQ(cells.back(), Cell(int(std::floor(x1)), int(std::floor(y1))))
        << "end cell is not last";
    for (std::size_t i = 1; i < cells.size(); ++i) {
      const int step = std::abs(cells[i].first - cells[i - 1].first) +
                       std::abs(cells[i].second - cells[i - 1].second);
      EXPECT_EQ(step, 1) << "cells " << i - 1 << " and " << i << " are not neighbours (trial "
                         << trial << ")";
    }
    const std::set<Cell> got(cells.begin(), cells.end());
    EXPECT_EQ(got.size(), cells.size()) << "a cell is visited twice";
    // Dense sampling of the segment: every sampled cell is visited.
    for (int s = 0; s <= 4000; ++s) {
      const double t = s / 4000.0;
      const Cell c{int(std::floor(x0 + t * (x1 - x0))), int(std::floor(y0 + t * (y1 - y0)))};
      EXPECT_TRUE(got.count(c)) << "sampled cell (" << c.first << ", " << c.second
                                << ") missing, trial " << trial;
    }
    // Exactly the crossed cells.
    std::set<Cell> ambiguous;
    const std::set<Cell> want = ExactCells(x0, y0, x1, y1, &ambiguous);
    for (const Cell& c : want) EXPECT_TRUE(got.count(c)) << "trial " << trial;
    for (const Cell& c : got)
      EXPECT_TRUE(want.count(c) || ambiguous.count(c))
          << "(" << c.first << ", " << c.second << ") not crossed, trial " << trial;
  }
  TraverseCells(2.5, 3.5, 2.7, 3.1, &cells);  // within one cell
  EXPECT_EQ(cells, (std::vector<Cell>{{2, 3}}));
}

GridMapConfig SmallGrid() {
  GridMapConfig c;
  c.x_min = 0;
  c.x_max = 5;
  c.y_min = 0;
  c.y_max = 4;
  c.resolution = 0.1;  // 50 x 40 cells
  c.max_range = 10;
  return c;
}

LaserScan Beams(double x, double y, double theta, std::vector<double> angles,
                std::vector<double> ranges) {
  // One scan whose beams are at the given angles (relative to theta): one beam per scan entry
  // via angle_min when there is a single angle, else evenly spaced.
  LaserScan s;
  s.x = x;
  s.y = y;
  s.theta = theta;
  s.angle_min = angles.front();
  s.angle_increment = angles.size() > 1 ? angles[1] - angles[0] : 0.0;
  s.ranges = std::move(ranges);
  return s;
}

// A cell's probability as queries answer it (unknown cells are NaN in cells(), answered as 0.5).
float At(const GridMap& g, int ix, int iy) {
  const float p = g.cells()(iy, ix);
  return std::isnan(p) ? 0.5f : p;
}

TEST(GridBuilder, OneBeamMarksItsEndCellHitAndTheCellsBeforeItFree) {
  const GridMapConfig c = SmallGrid();
  // From the middle of cell (5, 5) along +x for 2 m: end in cell (25, 5).
  const GridMap g = BuildGridMap(c, {Beams(0.55, 0.55, 0.0, {0.0}, {2.0})});
  EXPECT_EQ(g.geometry().nx, 50);
  EXPECT_EQ(g.geometry().ny, 40);
  for (int ix = 0; ix < 50; ++ix) {
    for (int iy = 0; iy < 40; ++iy) {
      const float want = iy == 5 && ix >= 5 && ix < 25 ? 0.4f : iy == 5 && ix == 25 ? 0.7f : 0.5f;
      EXPECT_NEAR(At(g, ix, iy), want, 1e-6) << ix << ", " << iy;
    }
  }
  // A diagonal beam marks the cells TraverseCells names (in cell units from the origin).
  const double r = 2.3, a = 0.61;
  const GridMap d = BuildGridMap(c, {Beams(1.23, 0.77, a, {0.0}, {r})});
  std::vector<std::pair<int, int>> ray;
  const double ox = 1.23 / 0.1, oy = 0.77 / 0.1;  // the builder's own grid coordinates
  TraverseCells(ox, oy, ox + r * std::cos(a) / 0.1, oy + r * std::sin(a) / 0.1, &ray);
  ASSERT_GT(ray.size(), 20u);
  int free = 0;
  for (std::size_t i = 0; i < ray.size(); ++i) {
    EXPECT_NEAR(At(d, ray[i].first, ray[i].second), i + 1 == ray.size() ? 0.7f : 0.4f, 1e-6);
    free += i + 1 < ray.size();
  }
  int marked = 0;
  for (Eigen::Index i = 0; i < d.cells().size(); ++i) marked += !std::isnan(d.cells().data()[i]);
  EXPECT_EQ(marked, free + 1);
}

TEST(GridBuilder, RepeatedScansAccumulateLogOddsAndClamp) {
  const GridMapConfig c = SmallGrid();
  const LaserScan s = Beams(0.55, 0.55, 0.0, {0.0}, {2.0});
  const auto logit = [](double p) { return std::log(p / (1 - p)); };
  const auto sigmoid = [](double l) { return 1 / (1 + std::exp(-l)); };
  for (int scans = 1; scans <= 8; ++scans) {
    const GridMap g = BuildGridMap(c, std::vector<LaserScan>(scans, s));
    const double hit = sigmoid(std::min(scans * logit(0.7), logit(0.97)));
    const double miss = sigmoid(std::max(scans * logit(0.4), logit(0.12)));
    EXPECT_NEAR(At(g, 25, 5), hit, 1e-6) << scans;
    EXPECT_NEAR(At(g, 10, 5), miss, 1e-6) << scans;
  }
  const GridMap many = BuildGridMap(c, std::vector<LaserScan>(50, s));
  EXPECT_NEAR(At(many, 25, 5), 0.97, 1e-6);
  EXPECT_NEAR(At(many, 5, 5), 0.12, 1e-6);
  // Clamping makes a cell recoverable: after 50 hits, 3 misses move it (OctoMap behaviour).
  std::vector<LaserScan> then_free(50, s);
  for (int i = 0; i < 3; ++i) then_free.push_back(Beams(0.55, 0.55, 0.0, {0.0}, {3.0}));
  const GridMap back = BuildGridMap(c, then_free);
  EXPECT_NEAR(At(back, 25, 5), sigmoid(logit(0.97) + 3 * logit(0.4)), 1e-6);
}

TEST(GridBuilder, WithinOneScanACellIsUpdatedOnceAndOccupiedWins) {
  const GridMapConfig c = SmallGrid();
  // Beam 0 ends in cell (25, 5); beam 1 (same direction, longer) passes through it.
  const LaserScan s = Beams(0.55, 0.55, 0.0, {0.0, 0.0}, {2.0, 3.0});
  const GridMap g = BuildGridMap(c, {s});
  EXPECT_NEAR(At(g, 25, 5), 0.7, 1e-6);  // one hit, not hit + miss
  EXPECT_NEAR(At(g, 20, 5), 0.4, 1e-6);  // one miss, not two
  EXPECT_NEAR(At(g, 35, 5), 0.7, 1e-6);
  EXPECT_NEAR(At(g, 30, 5), 0.4, 1e-6);
}

TEST(GridBuilder, BeamsWithoutAReturnAndBadPosesAreSkipped) {
  GridMapConfig c = SmallGrid();
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  std::vector<LaserScan> scans = {
      Beams(2.05, 2.05, 0.3, {0.0, 0.5, 1.0, 1.5, 2.0, 2.5}, {0.0, -1.0, inf, nan, 10.0, 12.0}),
      Beams(nan, 2.05, 0.0, {0.0}, {1.0}), Beams(2.05, 2.05, inf, {0.0}, {1.0})};
  for (const CellType type : {CellType::kFloat32, CellType::kUint8}) {
    c.cell_type = type;
    const GridMap g = BuildGridMap(c, scans);
    EXPECT_TRUE(g.cells().array().isNaN().all());
    testing::TempDir dir;
    g.Save(dir.File("g.h5"), "model: occupancy.grid\n", 0);
    const GridMap loaded = GridMap::Load(dir.File("g.h5"));
    EXPECT_TRUE(loaded.cells().array().isNaN().all());
    MapWorkspace ws;
    EXPECT_EQ(loaded.Query(2.0, 2.0, &ws).probability, 0.5);
  }
}

TEST(GridBuilder, UnknownCellsAreOneHalfAfterLoadAndBeamsLeavingTheGridAreCut) {
  GridMapConfig c = SmallGrid();
  // A beam from inside to far outside: cells outside are dropped, its end is not in the grid.
  const std::vector<LaserScan> scans = {Beams(4.55, 0.55, 0.0, {0.0, 1.5707963}, {3.0, 1.0})};
  for (const CellType type : {CellType::kFloat32, CellType::kUint8}) {
    c.cell_type = type;
    const GridMap g = BuildGridMap(c, scans);
    testing::TempDir dir;
    g.Save(dir.File("g.h5"), "model: occupancy.grid\n", 0);
    const GridMap loaded = GridMap::Load(dir.File("g.h5"));
    EXPECT_EQ(loaded.cell_type(), type);
    const double tol = type == CellType::kUint8 ? 0.5 / 254 : 1e-6;
    for (int ix = 45; ix < 50; ++ix) EXPECT_NEAR(At(loaded, ix, 5), 0.4, tol) << ix;
    EXPECT_NEAR(At(loaded, 45, 15), 0.7, tol);        // end of the second beam (4.55, 1.55)
    EXPECT_TRUE(std::isnan(loaded.cells()(20, 20)));  // never seen: stored as unknown
    EXPECT_EQ(At(loaded, 0, 0), 0.5f);
  }
  c.x_max = c.x_min;
  testing::ExpectErrorContains([&] { BuildGridMap(c, scans); }, {"empty extent"});
}

}  // namespace
}  // namespace foresight::occupancy
