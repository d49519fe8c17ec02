// OTNet's map encoding (thesis ch 6, "Encoding of Environmental Occupancy"): edge cells on
// hand-made grids; the OpenCV distance field and the one-sided Hausdorff distance read off it
// against brute force on many random grids (square and not); the encoder's distances against brute
// force for every database map (random maps, and real Occ-Traj120 maps when ../shared/data is
// there), its symmetry, phi in (0, 1], nearest-map look-up; and the errors, each naming what.

#include "inference/otnet/map_encoding.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include "tests/test_util.h"

namespace foresight::otnet {
namespace {

using foresight::testing::ExpectErrorContains;

/// A grid from rows of '#' (occupied) and '.' (free).
BinaryGrid GridFromText(const std::vector<std::string>& rows) {
  BinaryGrid g(static_cast<int>(rows.front().size()), static_cast<int>(rows.size()));
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) g.at(r, c) = rows[r][c] == '#' ? 1 : 0;
  return g;
}

/// Independent Bernoulli cells with P(occupied) = density.
BinaryGrid RandomGrid(int width, int height, double density, std::mt19937_64* rng) {
  std::bernoulli_distribution occupied(density);
  BinaryGrid g(width, height);
  for (auto& v : g.cells) v = occupied(*rng) ? 1 : 0;
  return g;
}

/// A map shaped like Occ-Traj120's: occupied border and random rectangular obstacles.
BinaryGrid RandomRooms(int width, int height, std::mt19937_64* rng) {
  BinaryGrid g(width, height);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      g.at(r, c) = (r < 2 || c < 2 || r >= height - 2 || c >= width - 2) ? 1 : 0;
  std::uniform_int_distribution<int> count(2, 6), col(0, width - 1), row(0, height - 1), size(2, 9);
  const int n = count(*rng);
  for (int k = 0; k < n; ++k) {
    const int c0 = col(*rng), r0 = row(*rng), w = size(*rng), h = size(*rng);
    for (int r = r0; r < std::min(height, r0 + h); ++r)
      for (int c = c0; c < std::min(width, c0 + w); ++c) g.at(r, c) = 1;
  }
  return g;
}

/// The test's own brute-force distance field: min over edges of the Euclidean distance, per cell.
std::vector<double> BruteField(const std::vector<Eigen::Vector2i>& edges, int width, int height) {
  std::vector<double> f(static_cast<size_t>(width) * height);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& e : edges) best = std::min(best, std::hypot(c - e.x(), r - e.y()));
      f[static_cast<size_t>(r) * width + c] = best;
    }
  return f;
}

TEST(EdgeCells, HandMadeGrids) {
  EXPECT_TRUE(EdgeCells(GridFromText({"....", "....", "...."})).empty());
  EXPECT_TRUE(EdgeCells(GridFromText({"####", "####", "####"})).empty());

  // A 3 x 3 block: its ring of 8 cells is the edge, the centre is not (row-major order).
  const auto block = EdgeCells(GridFromText({".....", ".###.", ".###.", ".###.", "....."}));
  const std::vector<Eigen::Vector2i> ring = {{1, 1}, {2, 1}, {3, 1}, {1, 2},
                                             {3, 2}, {1, 3}, {2, 3}, {3, 3}};
  EXPECT_EQ(block, ring);

  // One free cell in the middle of an occupied grid: only its four 4-neighbours are edges; the
  // diagonal corners are not, and the outside of the grid does not make the border an edge.
  const auto hole = EdgeCells(GridFromText({"###", "#.#", "###"}));
  const std::vector<Eigen::Vector2i> cross = {{1, 0}, {0, 1}, {2, 1}, {1, 2}};
  EXPECT_EQ(hole, cross);

  // Non-square, (col, row) order: the bottom-left cell's only neighbours inside the grid are
  // occupied, so it is not an edge although it lies on the border.
  const auto column = EdgeCells(GridFromText({"#....", "#....", "##..."}));
  const std::vector<Eigen::Vector2i> expected = {{0, 0}, {0, 1}, {1, 2}};
  EXPECT_EQ(column, expected);
}

TEST(EdgeCells, RejectsAGridWhoseCellsDoNotMatchItsSize) {
  BinaryGrid g(4, 3);
  g.cells.pop_back();
  ExpectErrorContains([&] { EdgeCells(g); }, {"EdgeCells", "11 cells", "12"});
}

TEST(EdgeDistanceField, IsTheExactEuclideanDistanceOnRandomEdgeSets) {
  std::mt19937_64 rng(11);
  const std::vector<std::pair<int, int>> sizes = {{40, 40}, {23, 57}, {61, 9}, {1, 7}, {5, 1}};
  for (const auto& [w, h] : sizes) {
    for (int trial = 0; trial < 8; ++trial) {
      std::uniform_int_distribution<int> count(1, 12), col(0, w - 1), row(0, h - 1);
      std::vector<Eigen::Vector2i> edges;
      const int n = trial == 0 ? 1 : count(rng);  // one edge: the far corner is far
      for (int k = 0; k < n; ++k) edges.emplace_back(col(rng), row(rng));
      std::vector<float> field;
      EdgeDistanceField(edges, w, h, &field);
      const std::vector<double> brute = BruteField(edges, w, h);
      ASSERT_EQ(field.size(), brute.size());
      for (size_t i = 0; i < brute.size(); ++i)
        ASSERT_NEAR(field[i], brute[i], 1e-4)
            << w << " x " << h << " trial " << trial << " cell " << i;
    }
  }
}

TEST(EdgeDistanceField, ReusesASizedOutput) {
  std::vector<float> field(12, -1.0f);
  const float* data = field.data();
  EdgeDistanceField({{0, 0}}, 4, 3, &field);
  EXPECT_EQ(field.data(), data);
  EXPECT_NEAR(field[11], std::hypot(3.0, 2.0), 1e-6);
}

TEST(OneSidedHausdorff, BruteForceOnHandCases) {
  EXPECT_DOUBLE_EQ(OneSidedHausdorffBruteForce({{0, 0}}, {{3, 4}}), 5.0);
  // h(A, B) = 10 (the far point of A), h(B, A) = 0: not symmetric; the average is 5.
  EXPECT_DOUBLE_EQ(OneSidedHausdorffBruteForce({{0, 0}, {10, 0}}, {{0, 0}}), 10.0);
  EXPECT_DOUBLE_EQ(OneSidedHausdorffBruteForce({{0, 0}}, {{0, 0}, {10, 0}}), 0.0);
  EXPECT_DOUBLE_EQ(AveragedHausdorffBruteForce({{0, 0}, {10, 0}}, {{0, 0}}), 5.0);
  // Max over A of min over B: A's second point is 2 from B's nearest.
  EXPECT_DOUBLE_EQ(OneSidedHausdorffBruteForce({{1, 1}, {5, 1}}, {{1, 2}, {7, 1}, {20, 20}}), 2.0);
}

TEST(OneSidedHausdorff, ViaTheFieldEqualsTheDefinitionOnRandomGrids) {
  int compared = 0;
  for (std::uint64_t seed = 0; seed < 60; ++seed) {
    std::mt19937_64 rng(seed);
    const bool square = seed % 2 == 0;
    const int w = square ? 40 : 27, h = square ? 40 : 44;
    std::uniform_real_distribution<double> density(0.02, 0.7);
    const BinaryGrid ga = RandomGrid(w, h, density(rng), &rng);
    const BinaryGrid gb =
        seed % 3 == 0 ? RandomRooms(w, h, &rng) : RandomGrid(w, h, density(rng), &rng);
    const auto a = EdgeCells(ga), b = EdgeCells(gb);
    if (a.empty() || b.empty()) continue;
    std::vector<float> field_a, field_b;
    EdgeDistanceField(a, w, h, &field_a);
    EdgeDistanceField(b, w, h, &field_b);
    const double ab = OneSidedHausdorff(a, field_b, w), ba = OneSidedHausdorff(b, field_a, w);
    EXPECT_NEAR(ab, OneSidedHausdorffBruteForce(a, b), 1e-4) << "seed " << seed;
    EXPECT_NEAR(ba, OneSidedHausdorffBruteForce(b, a), 1e-4) << "seed " << seed;
    // The averaged distance is symmetric and the mean of the one-sided ones.
    EXPECT_DOUBLE_EQ(AveragedHausdorffBruteForce(a, b), AveragedHausdorffBruteForce(b, a));
    EXPECT_NEAR(AveragedHausdorffBruteForce(a, b), 0.5 * (ab + ba), 1e-4);
    ++compared;
  }
  EXPECT_GE(compared, 55);
}

TEST(OneSidedHausdorff, Errors) {
  const std::vector<float> field(12, 0.0f);
  ExpectErrorContains([&] { OneSidedHausdorff({}, field, 4); }, {"OneSidedHausdorff", "empty"});
  ExpectErrorContains(
      [&] {
        OneSidedHausdorff({{4, 0}}, field, 4);
      },
      {"OneSidedHausdorff", "point 0", "col 4", "4 x 3"});
  ExpectErrorContains(
      [&] {
        OneSidedHausdorff({{0, 0}}, field, 5);
      },
      {"OneSidedHausdorff", "12 values", "width 5"});
  ExpectErrorContains([&] { OneSidedHausdorffBruteForce({}, {{0, 0}}); }, {"set A is empty"});
  ExpectErrorContains([&] { OneSidedHausdorffBruteForce({{0, 0}}, {}); }, {"set B is empty"});
  std::vector<float> out;
  ExpectErrorContains([&] { EdgeDistanceField({}, 4, 3, &out); },
                      {"EdgeDistanceField", "no edge cells"});
  ExpectErrorContains(
      [&] {
        EdgeDistanceField({{1, 1}, {2, 3}}, 4, 3, &out);
      },
      {"EdgeDistanceField", "edge 1", "row 3", "4 x 3"});
  ExpectErrorContains(
      [&] {
        EdgeDistanceField({{0, 0}}, 0, 3, &out);
      },
      {"EdgeDistanceField", "0 x 3"});
}

/// Checks every database distance of `query` against brute force and the similarities against
/// S_H of those distances.
void ExpectEncoderMatchesBruteForce(const MapEncoder& encoder, const BinaryGrid& query) {
  MapEncoder::Workspace ws = encoder.MakeWorkspace();
  Eigen::VectorXd distances(encoder.size()), phi(encoder.size());
  encoder.Distances(query, &ws, distances);
  encoder.Encode(query, &ws, phi);
  const auto q = EdgeCells(query);
  for (int m = 0; m < encoder.size(); ++m) {
    const double brute = AveragedHausdorffBruteForce(q, EdgeCells(encoder.database()[m]));
    EXPECT_NEAR(distances[m], brute, 1e-4) << "database map " << m;
    EXPECT_NEAR(phi[m], std::exp(-brute * brute / (2 * encoder.length_scale())), 1e-6);
    EXPECT_GT(phi[m], 0.0);
    EXPECT_LE(phi[m], 1.0);
  }
}

TEST(MapEncoder, DistancesMatchBruteForceForEveryDatabaseMap) {
  std::mt19937_64 rng(5);
  std::vector<BinaryGrid> database;
  for (int m = 0; m < 12; ++m)
    database.push_back(m % 2 ? RandomRooms(40, 40, &rng) : RandomGrid(40, 40, 0.3, &rng));
  const MapEncoder encoder(database, 9.0);
  EXPECT_EQ(encoder.size(), 12);
  EXPECT_EQ(encoder.width(), 40);
  EXPECT_EQ(encoder.height(), 40);
  for (int k = 0; k < 4; ++k) ExpectEncoderMatchesBruteForce(encoder, RandomRooms(40, 40, &rng));

  std::vector<BinaryGrid> wide;
  for (int m = 0; m < 5; ++m) wide.push_back(RandomRooms(31, 18, &rng));
  ExpectEncoderMatchesBruteForce(MapEncoder(wide, 2.5), RandomGrid(31, 18, 0.2, &rng));
}

/// Reads an Occ-Traj120 map: a 40 x 40 numpy print of 0/1 (brackets and spaces skipped).
BinaryGrid ReadOccTrajMap(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::uint8_t> cells;
  char ch;
  while (in.get(ch))
    if (ch == '0' || ch == '1') cells.push_back(ch == '1');
  BinaryGrid g(40, 40);
  if (cells.size() != g.cells.size()) return BinaryGrid();
  g.cells = cells;
  return g;
}

TEST(MapEncoder, DistancesMatchBruteForceOnRealMaps) {
  const std::string data = foresight::testing::SharedDataDir();
  const std::string dir = data.empty() ? "" : data + "/occ_traj120/maps";
  if (dir.empty() || !std::filesystem::is_directory(dir))
    GTEST_SKIP() << "../shared/data/occ_traj120/maps is absent: skipping the real maps";
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 10u);
  std::vector<BinaryGrid> maps;
  for (size_t i = 0; i < 10; ++i) {
    maps.push_back(ReadOccTrajMap(files[i]));
    ASSERT_EQ(maps.back().width, 40) << files[i];
  }
  const MapEncoder encoder(std::vector<BinaryGrid>(maps.begin(), maps.begin() + 8), 4.0);
  ExpectEncoderMatchesBruteForce(encoder, maps[8]);
  ExpectEncoderMatchesBruteForce(encoder, maps[9]);
}

TEST(MapEncoder, SymmetricDeltaAndUnitSimilarityForADatabaseMap) {
  std::mt19937_64 rng(8);
  const BinaryGrid a = RandomRooms(40, 40, &rng), b = RandomGrid(40, 40, 0.25, &rng);
  const MapEncoder on_a({a}, 3.0), on_b({b}, 3.0);
  auto ws_a = on_a.MakeWorkspace(), ws_b = on_b.MakeWorkspace();
  Eigen::VectorXd ab(1), ba(1);
  on_a.Distances(b, &ws_a, ab);
  on_b.Distances(a, &ws_b, ba);
  EXPECT_NEAR(ab[0], ba[0], 1e-6);
  EXPECT_GT(ab[0], 0.0);

  const MapEncoder encoder({b, a, RandomRooms(40, 40, &rng)}, 3.0);
  auto ws = encoder.MakeWorkspace();
  Eigen::VectorXd phi(3), d(3);
  encoder.Encode(a, &ws, phi);
  encoder.Distances(a, &ws, d);
  EXPECT_EQ(d[1], 0.0);
  EXPECT_EQ(phi[1], 1.0);
  EXPECT_LT(phi[0], 1.0);
  EXPECT_NEAR(phi[0], std::exp(-d[0] * d[0] / 6.0), 1e-12);
}

TEST(MapEncoder, NearestReturnsTheDuplicateAndTheLowestIndexOnTies) {
  std::mt19937_64 rng(9);
  std::vector<BinaryGrid> database;
  for (int m = 0; m < 7; ++m) database.push_back(RandomRooms(40, 40, &rng));
  const BinaryGrid query = database[4];
  const MapEncoder encoder(database, 5.0);
  auto ws = encoder.MakeWorkspace();
  EXPECT_EQ(encoder.Nearest(query, &ws), 4);
  // A second copy at index 6 and one at index 2: the lowest index wins.
  database[6] = query;
  database[2] = query;
  const MapEncoder ties(database, 5.0);
  auto ws2 = ties.MakeWorkspace();
  EXPECT_EQ(ties.Nearest(query, &ws2), 2);
  // Nearest agrees with the minimum of Distances for other queries.
  for (int k = 0; k < 5; ++k) {
    const BinaryGrid q = RandomRooms(40, 40, &rng);
    Eigen::VectorXd d(encoder.size());
    encoder.Distances(q, &ws, d);
    Eigen::Index best;
    d.minCoeff(&best);
    EXPECT_EQ(encoder.Nearest(q, &ws), static_cast<int>(best));
  }
}

TEST(MapEncoder, Errors) {
  std::mt19937_64 rng(10);
  const BinaryGrid good = RandomRooms(40, 40, &rng);
  ExpectErrorContains([] { MapEncoder({}, 1.0); }, {"MapEncoder", "database is empty"});
  ExpectErrorContains(
      [&] {
        MapEncoder({good, good, RandomRooms(40, 39, &rng)}, 1.0);
      },
      {"MapEncoder", "database map 2", "40 x 39", "40 x 40"});
  BinaryGrid free(40, 40);
  ExpectErrorContains(
      [&] {
        MapEncoder({good, free}, 1.0);
      },
      {"MapEncoder", "database map 1", "no edge cells"});
  ExpectErrorContains([&] { MapEncoder({good}, 0.0); }, {"MapEncoder", "l_H", "got 0"});
  ExpectErrorContains([&] { MapEncoder({good}, -2.0); }, {"MapEncoder", "l_H", "got -2"});
  ExpectErrorContains([&] { MapEncoder({good}, std::nan("")); }, {"MapEncoder", "l_H", "nan"});

  const MapEncoder encoder({good, RandomRooms(40, 40, &rng)}, 1.0);
  auto ws = encoder.MakeWorkspace();
  Eigen::VectorXd d(2), wrong(3);
  ExpectErrorContains([&] { encoder.Distances(RandomRooms(40, 30, &rng), &ws, d); },
                      {"MapEncoder", "40 x 30", "40 x 40"});
  ExpectErrorContains([&] { encoder.Distances(free, &ws, d); }, {"MapEncoder", "no edge cells"});
  ExpectErrorContains([&] { encoder.Nearest(free, &ws); }, {"MapEncoder", "no edge cells"});
  ExpectErrorContains([&] { encoder.Encode(good, &ws, wrong); },
                      {"MapEncoder", "3 entries", "2 maps"});
  ExpectErrorContains([&] { MapEncoder().Nearest(good, &ws); }, {"MapEncoder", "no database"});
}

}  // namespace
}  // namespace foresight::otnet
