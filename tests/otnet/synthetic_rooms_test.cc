// The synthetic rooms-and-corridors stand-in for Occ-Traj120 and its planner. Generator:
// determinism by seed, every waypoint free and inside, steps of 0.5-3 cells whose straight
// segment is free (sampled every 0.1 cell), maps with walls, free space in one piece and an
// entry in the border, starts in one region and ends in >= 2 exit regions (clustered here).
// Planner: path length on an empty grid equals the octile distance; on random grids its cost
// equals a brute-force Dijkstra's (with a brute-force distance to the nearest occupied cell);
// it never enters an occupied cell nor cuts a corner; unreachable gives an empty path.

#include "datasets/synthetic_rooms.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <random>

#include "tests/test_util.h"

namespace foresight::otnet {
namespace {

using foresight::testing::ExpectErrorContains;

constexpr double kSqrt2 = 1.41421356237309504880;

/// The defaults (60 maps x 50 trajectories), generated once for the whole binary.
const std::vector<MapTrajectories>& DefaultMaps() {
  static const std::vector<MapTrajectories> maps = GenerateRoomsAndCorridors({});
  return maps;
}

/// Whether the segment a-b is free when sampled every 0.1 cell (ends included).
bool SampledSegmentFree(const BinaryGrid& map, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.1)));
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector2d p = a + (static_cast<double>(i) / n) * (b - a);
    if (map.OccupiedAt(p.x(), p.y())) return false;
  }
  return true;
}

/// Number of 4-connected components of free cells (flood fill).
int FreeComponents(const BinaryGrid& map) {
  std::vector<int> label(map.cells.size(), -1);
  int components = 0;
  for (int s = 0; s < static_cast<int>(map.cells.size()); ++s) {
    if (map.cells[s] != 0 || label[s] >= 0) continue;
    std::vector<int> stack{s};
    label[s] = components;
    while (!stack.empty()) {
      const int u = stack.back();
      stack.pop_back();
      const int r = u / map.width, c = u % map.width;
      const int nr[4] = {r - 1, r + 1, r, r}, nc[4] = {c, c, c - 1, c + 1};
      for (int k = 0; k < 4; ++k) {
        if (!map.Inside(nr[k], nc[k])) continue;
        const int v = nr[k] * map.width + nc[k];
        if (map.cells[v] == 0 && label[v] < 0) {
          label[v] = components;
          stack.push_back(v);
        }
      }
    }
    ++components;
  }
  return components;
}

/// Sizes of the clusters of `points` by single linkage at `radius` (brute force).
std::vector<int> ClusterSizes(const std::vector<Eigen::Vector2d>& points, double radius) {
  std::vector<int> label(points.size(), -1);
  std::vector<int> sizes;
  for (std::size_t s = 0; s < points.size(); ++s) {
    if (label[s] >= 0) continue;
    const int id = static_cast<int>(sizes.size());
    sizes.push_back(0);
    std::vector<std::size_t> stack{s};
    label[s] = id;
    while (!stack.empty()) {
      const std::size_t u = stack.back();
      stack.pop_back();
      ++sizes[id];
      for (std::size_t v = 0; v < points.size(); ++v)
        if (label[v] < 0 && (points[u] - points[v]).norm() <= radius) {
          label[v] = id;
          stack.push_back(v);
        }
    }
  }
  return sizes;
}

bool SameMaps(const std::vector<MapTrajectories>& a, const std::vector<MapTrajectories>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].id != b[i].id || a[i].map.cells != b[i].map.cells ||
        a[i].trajectories.size() != b[i].trajectories.size())
      return false;
    for (std::size_t j = 0; j < a[i].trajectories.size(); ++j)
      if (a[i].trajectories[j] != b[i].trajectories[j]) return false;
  }
  return true;
}

// ------------------------------------------------------------------------------------------
// Generator.

TEST(SyntheticRooms, IsDeterministicBySeedAndMapsDoNotDependOnTheirCount) {
  SyntheticRoomsOptions o;
  o.maps = 6;
  o.trajectories_per_map = 10;
  o.seed = 11;
  const std::vector<MapTrajectories> a = GenerateRoomsAndCorridors(o);
  EXPECT_TRUE(SameMaps(a, GenerateRoomsAndCorridors(o)));
  o.seed = 12;
  const std::vector<MapTrajectories> b = GenerateRoomsAndCorridors(o);
  int same_maps = 0;
  for (std::size_t i = 0; i < a.size(); ++i) same_maps += a[i].map.cells == b[i].map.cells;
  EXPECT_EQ(same_maps, 0);
  // Map k is drawn from its own stream: the first 3 of 6 equal the 3 of a 3-map run.
  o.seed = 11;
  o.maps = 3;
  const std::vector<MapTrajectories> c = GenerateRoomsAndCorridors(o);
  EXPECT_TRUE(SameMaps(c, std::vector<MapTrajectories>(a.begin(), a.begin() + 3)));
}

TEST(SyntheticRooms, MapsHaveWallsFreeSpaceInOnePieceAndAnEntryInTheBorder) {
  const std::vector<MapTrajectories>& maps = DefaultMaps();
  ASSERT_EQ(maps.size(), 60u);
  std::vector<std::vector<std::uint8_t>> distinct;
  for (std::size_t k = 0; k < maps.size(); ++k) {
    const BinaryGrid& g = maps[k].map;
    EXPECT_EQ(maps[k].id, "synthetic_" + std::to_string(k));
    ASSERT_EQ(g.width, 40);
    ASSERT_EQ(g.height, 40);
    ASSERT_EQ(g.cells.size(), 1600u);
    // Edge cells: occupied cells with a free 4-neighbour.
    int edges = 0;
    for (int r = 0; r < 40; ++r)
      for (int c = 0; c < 40; ++c) {
        if (g.at(r, c) == 0) continue;
        bool edge = false;
        for (const auto& [dr, dc] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}})
          edge |= g.Inside(r + dr, c + dc) && g.at(r + dr, c + dc) == 0;
        edges += edge;
      }
    EXPECT_GT(edges, 40) << k;
    const int free_cells = 1600 - g.CountOccupied();
    EXPECT_GT(free_cells, 150) << k;
    EXPECT_LT(free_cells, 1300) << k;
    EXPECT_EQ(FreeComponents(g), 1) << k;
    // The border is a wall but for the entry: between 1 and 10 free border cells, in one run.
    int free_border = 0;
    for (int i = 0; i < 40; ++i)
      free_border +=
          (g.at(0, i) == 0) + (g.at(39, i) == 0) + (g.at(i, 0) == 0) + (g.at(i, 39) == 0);
    EXPECT_GE(free_border, 3) << k;
    EXPECT_LE(free_border, 5) << k;
    if (std::find(distinct.begin(), distinct.end(), g.cells) == distinct.end())
      distinct.push_back(g.cells);
  }
  EXPECT_EQ(distinct.size(), maps.size());
}

TEST(SyntheticRooms, WaypointsAreFreeAndStepsShortWithFreeStraightSegments) {
  double step_sum = 0;
  int steps = 0, shortest = 1000, longest = 0;
  std::vector<double> lengths;
  for (const MapTrajectories& m : DefaultMaps()) {
    ASSERT_EQ(m.trajectories.size(), 50u) << m.id;
    for (const Eigen::MatrixX2d& t : m.trajectories) {
      ASSERT_GE(t.rows(), 2) << m.id;
      shortest = std::min(shortest, static_cast<int>(t.rows()));
      longest = std::max(longest, static_cast<int>(t.rows()));
      lengths.push_back(static_cast<double>(t.rows()));
      for (Eigen::Index i = 0; i < t.rows(); ++i) {
        ASSERT_TRUE(t(i, 0) >= 0 && t(i, 0) < 40 && t(i, 1) >= 0 && t(i, 1) < 40) << m.id;
        ASSERT_FALSE(m.map.OccupiedAt(t(i, 0), t(i, 1))) << m.id << " waypoint " << i;
        if (i == 0) continue;
        const Eigen::Vector2d a = t.row(i - 1).transpose(), b = t.row(i).transpose();
        const double d = (b - a).norm();
        ASSERT_GE(d, 0.5) << m.id << " step " << i;
        ASSERT_LE(d, 3.0) << m.id << " step " << i;
        ASSERT_TRUE(SampledSegmentFree(m.map, a, b)) << m.id << " step " << i;
        step_sum += d;
        ++steps;
      }
    }
  }
  // Occ-Traj120-like: steps about 1.5 cells, lengths mostly 10-50 waypoints.
  EXPECT_NEAR(step_sum / steps, 1.5, 0.2);
  std::sort(lengths.begin(), lengths.end());
  EXPECT_GE(lengths[lengths.size() / 10], 8.0);
  EXPECT_LE(lengths[lengths.size() * 9 / 10], 50.0);
  EXPECT_GE(shortest, 3);
  EXPECT_LE(longest, 80);
}

TEST(SyntheticRooms, StartsShareOneRegionAndEndsFanOutToSeveralExits) {
  int fanning = 0;
  for (const MapTrajectories& m : DefaultMaps()) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    std::vector<Eigen::Vector2d> ends;
    for (const Eigen::MatrixX2d& t : m.trajectories) {
      mean += t.row(0).transpose();
      ends.push_back(t.row(t.rows() - 1).transpose());
    }
    mean /= static_cast<double>(m.trajectories.size());
    double var = 0;
    for (const Eigen::MatrixX2d& t : m.trajectories)
      var += (t.row(0).transpose() - mean).squaredNorm();
    const double start_std = std::sqrt(var / static_cast<double>(m.trajectories.size()));
    EXPECT_LT(start_std, 2.5) << m.id;  // both axes together (Occ-Traj120: ~1.6 per axis)
    // The entry is at the border of the map.
    const double border_gap = std::min({mean.x(), mean.y(), 40 - mean.x(), 40 - mean.y()});
    EXPECT_LT(border_gap, 4.0) << m.id;
    // Exit regions: single-linkage clusters of end points at 3 cells holding >= 10 % each.
    int exits = 0;
    for (int size : ClusterSizes(ends, 3.0)) exits += size >= 5;
    fanning += exits >= 2;
  }
  EXPECT_GE(fanning, 54) << "maps whose trajectories end in >= 2 exit regions (of 60)";
}

TEST(SyntheticRooms, OptionsChangeStepsAndStarts) {
  SyntheticRoomsOptions o;
  o.maps = 4;
  o.trajectories_per_map = 20;
  o.step = 1.0;
  o.start_spread = 0;
  o.jitter = 0;
  o.size = 24;
  for (const MapTrajectories& m : GenerateRoomsAndCorridors(o)) {
    ASSERT_EQ(m.map.width, 24);
    ASSERT_EQ(m.trajectories.size(), 20u);
    for (const Eigen::MatrixX2d& t : m.trajectories) {
      // No start spread: every trajectory starts at the same entry point.
      EXPECT_EQ(t.row(0), m.trajectories[0].row(0)) << m.id;
      for (Eigen::Index i = 1; i < t.rows(); ++i) {
        const double d = (t.row(i) - t.row(i - 1)).norm();
        EXPECT_GE(d, 1.0 / 3.0) << m.id;
        EXPECT_LE(d, 2.0) << m.id;
        EXPECT_TRUE(SampledSegmentFree(m.map, t.row(i - 1).transpose(), t.row(i).transpose()));
      }
    }
  }
}

TEST(SyntheticRooms, RejectsOptionsOutOfRange) {
  const auto expect = [](auto edit, const std::vector<std::string>& parts) {
    SyntheticRoomsOptions o;
    edit(o);
    ExpectErrorContains([&] { GenerateRoomsAndCorridors(o); }, parts);
  };
  expect([](SyntheticRoomsOptions& o) { o.size = 19; }, {"size", "19"});
  expect([](SyntheticRoomsOptions& o) { o.maps = 0; }, {"maps", "0"});
  expect([](SyntheticRoomsOptions& o) { o.trajectories_per_map = -1; },
         {"trajectories_per_map", "-1"});
  expect([](SyntheticRoomsOptions& o) { o.step = 0; }, {"step", "0"});
  expect([](SyntheticRoomsOptions& o) { o.step = 6; }, {"step", "6", "size / 8"});
  expect([](SyntheticRoomsOptions& o) { o.step = std::nan(""); }, {"step", "nan"});
  expect([](SyntheticRoomsOptions& o) { o.start_spread = -0.5; }, {"start_spread", "-0.5"});
  expect([](SyntheticRoomsOptions& o) { o.jitter = std::numeric_limits<double>::infinity(); },
         {"jitter", "inf"});
}

// ------------------------------------------------------------------------------------------
// Planner.

double PathLength(const Eigen::MatrixX2d& p) {
  double len = 0;
  for (Eigen::Index i = 1; i < p.rows(); ++i) len += (p.row(i) - p.row(i - 1)).norm();
  return len;
}

/// Every move goes to an 8-neighbour, enters a free cell and cuts no occupied corner.
void ExpectLegalMoves(const BinaryGrid& map, const Eigen::MatrixX2d& p) {
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const int r = static_cast<int>(std::floor(p(i, 1))), c = static_cast<int>(std::floor(p(i, 0)));
    ASSERT_TRUE(map.Inside(r, c));
    EXPECT_EQ(map.at(r, c), 0) << "path enters occupied cell " << r << "," << c;
    EXPECT_DOUBLE_EQ(p(i, 0), c + 0.5);  // cell centres
    EXPECT_DOUBLE_EQ(p(i, 1), r + 0.5);
    if (i == 0) continue;
    const int pr = static_cast<int>(std::floor(p(i - 1, 1)));
    const int pc = static_cast<int>(std::floor(p(i - 1, 0)));
    ASSERT_LE(std::max(std::abs(r - pr), std::abs(c - pc)), 1);
    ASSERT_GE(std::abs(r - pr) + std::abs(c - pc), 1);
    if (r != pr && c != pc) {
      EXPECT_EQ(map.at(pr, c), 0) << "corner cut at step " << i;
      EXPECT_EQ(map.at(r, pc), 0) << "corner cut at step " << i;
    }
  }
}

TEST(PlanGridPath, EmptyGridPathHasTheOctileLength) {
  const BinaryGrid empty(13, 9);
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector2i from(static_cast<int>(rng() % 9), static_cast<int>(rng() % 13));
    const Eigen::Vector2i to(static_cast<int>(rng() % 9), static_cast<int>(rng() % 13));
    const Eigen::MatrixX2d p = PlanGridPath(empty, from, to, 0.0);
    ASSERT_GE(p.rows(), 1);
    EXPECT_EQ(p.row(0), Eigen::RowVector2d(from.y() + 0.5, from.x() + 0.5));
    EXPECT_EQ(p.row(p.rows() - 1), Eigen::RowVector2d(to.y() + 0.5, to.x() + 0.5));
    const int dr = std::abs(from.x() - to.x()), dc = std::abs(from.y() - to.y());
    const double octile = std::max(dr, dc) + (kSqrt2 - 1) * std::min(dr, dc);
    EXPECT_NEAR(PathLength(p), octile, 1e-12);
    EXPECT_EQ(p.rows(), std::max(dr, dc) + 1);  // an optimal 8-connected path
    ExpectLegalMoves(empty, p);
  }
  // from == to: one point.
  EXPECT_EQ(PlanGridPath(empty, {4, 4}, {4, 4}, 1.0).rows(), 1);
}

/// Brute force: distance (centre to centre) to the nearest occupied cell, outside cells included.
std::vector<double> BruteDistance(const BinaryGrid& map) {
  std::vector<double> d(map.cells.size(), std::numeric_limits<double>::infinity());
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c)
      for (int orow = -1; orow <= map.height; ++orow)
        for (int ocol = -1; ocol <= map.width; ++ocol)
          if (!map.Inside(orow, ocol) || map.at(orow, ocol) != 0)
            d[r * map.width + c] = std::min(d[r * map.width + c], std::hypot(orow - r, ocol - c));
  return d;
}

/// Dijkstra over all cells with the documented move cost: length x mean of the two cells'
/// 1 + w / (1 + d). Returns the optimal cost (infinity when unreachable).
double DijkstraCost(const BinaryGrid& map, Eigen::Vector2i from, Eigen::Vector2i to, double w) {
  const std::vector<double> d = BruteDistance(map);
  const auto factor = [&](int cell) { return 1 + w / (1 + d[cell]); };
  std::vector<double> cost(map.cells.size(), std::numeric_limits<double>::infinity());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> q;
  const int s = from.x() * map.width + from.y();
  cost[s] = 0;
  q.emplace(0.0, s);
  while (!q.empty()) {
    const auto [cu, u] = q.top();
    q.pop();
    if (cu > cost[u]) continue;
    const int r = u / map.width, c = u % map.width;
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        if ((dr == 0 && dc == 0) || !map.Inside(r + dr, c + dc) || map.at(r + dr, c + dc) != 0)
          continue;
        if (dr != 0 && dc != 0 && (map.at(r + dr, c) != 0 || map.at(r, c + dc) != 0)) continue;
        const int v = (r + dr) * map.width + c + dc;
        const double cv = cu + std::hypot(dr, dc) * 0.5 * (factor(u) + factor(v));
        if (cv < cost[v]) {
          cost[v] = cv;
          q.emplace(cv, v);
        }
      }
  }
  return cost[to.x() * map.width + to.y()];
}

/// The documented cost of a returned path (brute-force distances).
double PathCost(const BinaryGrid& map, const Eigen::MatrixX2d& p, double w) {
  const std::vector<double> d = BruteDistance(map);
  const auto factor = [&](Eigen::Index i) {
    const int cell =
        static_cast<int>(std::floor(p(i, 1))) * map.width + static_cast<int>(std::floor(p(i, 0)));
    return 1 + w / (1 + d[cell]);
  };
  double cost = 0;
  for (Eigen::Index i = 1; i < p.rows(); ++i)
    cost += (p.row(i) - p.row(i - 1)).norm() * 0.5 * (factor(i - 1) + factor(i));
  return cost;
}

TEST(PlanGridPath, CostEqualsBruteForceDijkstraOnRandomGrids) {
  std::mt19937_64 rng(17);
  int solved = 0, unreachable = 0;
  for (int trial = 0; trial < 60; ++trial) {
    BinaryGrid g(14, 11);
    for (std::uint8_t& v : g.cells) v = (rng() % 100) < 30 ? 1 : 0;
    std::vector<int> free_cells;
    for (int i = 0; i < static_cast<int>(g.cells.size()); ++i)
      if (g.cells[i] == 0) free_cells.push_back(i);
    const int a = free_cells[rng() % free_cells.size()], b = free_cells[rng() % free_cells.size()];
    const Eigen::Vector2i from(a / 14, a % 14), to(b / 14, b % 14);
    for (double w : {0.0, 2.0, 10.0}) {
      const double best = DijkstraCost(g, from, to, w);
      const Eigen::MatrixX2d p = PlanGridPath(g, from, to, w);
      if (std::isinf(best)) {
        EXPECT_EQ(p.rows(), 0) << "trial " << trial;
        ++unreachable;
        continue;
      }
      ASSERT_GE(p.rows(), 1) << "trial " << trial;
      ExpectLegalMoves(g, p);
      // The distance transform is single precision: compare costs to 1e-5 relative.
      EXPECT_NEAR(PathCost(g, p, w), best, 1e-5 * std::max(1.0, best)) << "trial " << trial;
      ++solved;
    }
  }
  EXPECT_GT(solved, 60);
  EXPECT_GT(unreachable, 0);  // the 30 % random grids include split ones
}

TEST(PlanGridPath, ClearanceWeightPullsThePathFromTheWalls) {
  // A 9-wide open room: from one corner region to the other, the weighted path keeps off the
  // walls (larger mean distance to them) at the price of a longer path.
  BinaryGrid g(20, 9);
  const Eigen::MatrixX2d plain = PlanGridPath(g, {0, 0}, {0, 19}, 0.0);
  const Eigen::MatrixX2d kept = PlanGridPath(g, {0, 0}, {0, 19}, 5.0);
  EXPECT_NEAR(PathLength(plain), 19.0, 1e-12);
  EXPECT_GT(PathLength(kept), PathLength(plain));
  EXPECT_GT(kept.col(1).mean(), plain.col(1).mean() + 1.0);
}

TEST(PlanGridPath, UnreachableGoalGivesAnEmptyPath) {
  BinaryGrid g(7, 5);
  for (int r = 0; r < 5; ++r) g.at(r, 3) = 1;  // a wall splits the grid
  EXPECT_EQ(PlanGridPath(g, {2, 0}, {2, 6}, 0.0).rows(), 0);
  EXPECT_EQ(PlanGridPath(g, {2, 0}, {2, 6}, 3.0).rows(), 0);
  // Diagonal neighbours across two occupied corners are not connected either.
  BinaryGrid d(2, 2);
  d.at(0, 1) = 1;
  d.at(1, 0) = 1;
  EXPECT_EQ(PlanGridPath(d, {0, 0}, {1, 1}, 0.0).rows(), 0);
  d.at(1, 0) = 0;
  const Eigen::MatrixX2d p = PlanGridPath(d, {0, 0}, {1, 1}, 0.0);
  ASSERT_EQ(p.rows(), 3);  // around the corner, not across it
  ExpectLegalMoves(d, p);
}

TEST(PlanGridPath, RejectsBadEndsAndWeights) {
  BinaryGrid g(6, 4);
  g.at(1, 1) = 1;
  ExpectErrorContains(
      [&] {
        PlanGridPath(g, {4, 0}, {0, 0}, 0.0);
      },
      {"from", "row 4", "col 0", "outside", "6 x 4"});
  ExpectErrorContains([&] { PlanGridPath(g, {0, 0}, {0, -1}, 0.0); }, {"to", "col -1", "outside"});
  ExpectErrorContains([&] { PlanGridPath(g, {1, 1}, {0, 0}, 0.0); }, {"from", "row 1", "occupied"});
  ExpectErrorContains([&] { PlanGridPath(g, {0, 0}, {1, 1}, 0.0); }, {"to", "occupied"});
  ExpectErrorContains([&] { PlanGridPath(g, {0, 0}, {2, 2}, -1.0); }, {"clearance_weight", "-1"});
  ExpectErrorContains(
      [&] {
        PlanGridPath(g, {0, 0}, {2, 2}, std::nan(""));
      },
      {"clearance_weight", "nan"});
  ExpectErrorContains([&] { PlanGridPath(BinaryGrid(), {0, 0}, {0, 0}, 0.0); }, {"0 x 0"});
}

}  // namespace
}  // namespace foresight::otnet
