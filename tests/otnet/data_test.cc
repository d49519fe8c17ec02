// The Occ-Traj120 reader and the map-level splits (thesis ch 6). On the shipped data (skipped when
// ../shared/data is absent): the README's indexing convention (every waypoint free with
// map[floor(y)][floor(x)], a clear share not with the transpose), the counts and lengths, and
// values read by hand from the files. On files written here: every error names the file and the
// line, and the drop policy counts what it drops. SplitMaps: determinism, a partition, sizes by
// the rounding rule, uniform placement over seeds (Monte Carlo), errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "datasets/occ_traj.h"
#include "tests/test_util.h"

namespace foresight::otnet {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::TempDir;
using foresight::testing::WriteText;

/// ../shared/data/occ_traj120, or "" when absent.
std::string OccTrajRoot() {
  const std::string data = foresight::testing::SharedDataDir();
  if (data.empty()) return "";
  const std::string root = data + "/occ_traj120";
  return std::filesystem::is_regular_file(root + "/train_maps.txt") ? root : "";
}

#define SKIP_WITHOUT_OCC_TRAJ(root)                                                    \
  const std::string root = OccTrajRoot();                                              \
  if (root.empty())                                                                    \
  GTEST_SKIP() << "../shared/data/occ_traj120 is absent (set FORESIGHT_SOURCE_DIR to " \
                  "the repository root next to shared/): skipping the real Occ-Traj120 data"

// ------------------------------------------------------------------------------------------
// Real data.

TEST(OccTraj, ListsThe368ShippedMaps) {
  SKIP_WITHOUT_OCC_TRAJ(root);
  const std::vector<std::string> ids = ListOccTrajMaps(root);
  ASSERT_EQ(ids.size(), 368u);
  EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), ids.size());
  EXPECT_EQ(ids.front(), "0209bae1c9");
  for (const std::string& id : ids) {
    ASSERT_EQ(id.size(), 10u) << id;  // first 10 hex characters of an MD5
    EXPECT_TRUE(std::all_of(id.begin(), id.end(), [](char c) {
      return std::isxdigit(static_cast<unsigned char>(c)) != 0;
    })) << id;
  }
}

TEST(OccTraj, ValuesReadByHandFromTheFirstMap) {
  SKIP_WITHOUT_OCC_TRAJ(root);
  ReadReport report;
  const MapTrajectories m =
      LoadOccTrajMap(root, "0209bae1c9", 40, BadWaypointPolicy::kError, &report);
  EXPECT_EQ(m.id, "0209bae1c9");
  ASSERT_EQ(m.map.width, 40);
  ASSERT_EQ(m.map.height, 40);
  // Text row 0 is "1" x 21, "0" x 6, "1" x 13: the entry gap in the top wall.
  for (int c = 0; c < 40; ++c) EXPECT_EQ(m.map.at(0, c), (c >= 21 && c <= 26) ? 0 : 1) << c;
  // Row 5 is 1 1 1, 0 x 24, 1, 0 x 10, 1 1.
  for (int c = 0; c < 40; ++c)
    EXPECT_EQ(m.map.at(5, c), (c < 3 || c == 27 || c >= 38) ? 1 : 0) << c;
  // traj-0: 13 waypoints from (24.42, 1.93) to (9.99, 4.55); traj-1 has 25.
  ASSERT_EQ(m.trajectories.size(), 200u);
  const Eigen::MatrixX2d& t0 = m.trajectories[0];
  ASSERT_EQ(t0.rows(), 13);
  EXPECT_DOUBLE_EQ(t0(0, 0), 24.42);
  EXPECT_DOUBLE_EQ(t0(0, 1), 1.93);
  EXPECT_DOUBLE_EQ(t0(12, 0), 9.99);
  EXPECT_DOUBLE_EQ(t0(12, 1), 4.55);
  EXPECT_EQ(m.trajectories[1].rows(), 25);
  EXPECT_EQ(report.trajectories, 200);
  EXPECT_EQ(report.kept, 200);
}

TEST(OccTraj, WaypointsAreFreeUnderTheReadmeConventionNotItsTranspose) {
  SKIP_WITHOUT_OCC_TRAJ(root);
  const std::vector<std::string> ids = ListOccTrajMaps(root);
  int waypoints = 0, transposed_occupied = 0;
  for (std::size_t i = 0; i < 5; ++i) {
    // kDrop keeps every trajectory only if every waypoint is inside and free under
    // occupied(x, y) = map[floor(y)][floor(x)]; also checked directly below.
    ReadReport report;
    const MapTrajectories m = LoadOccTrajMap(root, ids[i], 40, BadWaypointPolicy::kDrop, &report);
    EXPECT_EQ(report.kept, report.trajectories) << ids[i];
    for (const Eigen::MatrixX2d& t : m.trajectories)
      for (Eigen::Index k = 0; k < t.rows(); ++k) {
        const double x = t(k, 0), y = t(k, 1);
        ++waypoints;
        EXPECT_FALSE(m.map.OccupiedAt(x, y)) << ids[i] << " (" << x << ", " << y << ")";
        EXPECT_EQ(m.map.at(static_cast<int>(std::floor(y)), static_cast<int>(std::floor(x))), 0);
        transposed_occupied +=
            m.map.at(static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y))) != 0;
      }
  }
  ASSERT_GT(waypoints, 1000);
  // The README reports 67 % free under map[x][y] over the whole data set.
  EXPECT_GT(static_cast<double>(transposed_occupied) / waypoints, 0.1)
      << transposed_occupied << " of " << waypoints;
}

TEST(OccTraj, EveryMapHas200TrajectoriesOf5To58Waypoints) {
  SKIP_WITHOUT_OCC_TRAJ(root);
  const std::vector<std::string> ids = ListOccTrajMaps(root);
  ReadReport total;
  int shortest = 1000, longest = 0;
  for (const std::string& id : ids) {
    ReadReport report;
    const MapTrajectories m = LoadOccTrajMap(root, id, 40, BadWaypointPolicy::kDrop, &report);
    ASSERT_EQ(m.trajectories.size(), 200u) << id;
    EXPECT_EQ(report.trajectories, 200) << id;
    EXPECT_GT(m.map.CountOccupied(), 0) << id;
    EXPECT_LT(m.map.CountOccupied(), 1600) << id;
    for (const Eigen::MatrixX2d& t : m.trajectories) {
      shortest = std::min(shortest, static_cast<int>(t.rows()));
      longest = std::max(longest, static_cast<int>(t.rows()));
    }
    total.Add(report);
  }
  EXPECT_EQ(total.trajectories, 368 * 200);
  EXPECT_EQ(total.kept, 368 * 200);
  EXPECT_EQ(total.dropped_outside + total.dropped_occupied + total.dropped_too_short, 0);
  EXPECT_EQ(shortest, 5);
  EXPECT_EQ(longest, 58);
}

// ------------------------------------------------------------------------------------------
// Maps written here.

constexpr const char* kSmallMap =
    "[[1 1 1 1 1]\n"
    " [1 0 0 0 1]\n"
    " [1 0 1 0 1]\n"
    " [1 1 1 1 1]]";

TEST(OccTrajMap, ReadsRowsAsYAndColumnsAsX) {
  TempDir dir;
  WriteText(dir.File("m.txt"), kSmallMap);
  const BinaryGrid g = ReadOccTrajMap(dir.File("m.txt"), 5, 4);
  ASSERT_EQ(g.width, 5);
  ASSERT_EQ(g.height, 4);
  const int expected[4][5] = {{1, 1, 1, 1, 1}, {1, 0, 0, 0, 1}, {1, 0, 1, 0, 1}, {1, 1, 1, 1, 1}};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 5; ++c) {
      EXPECT_EQ(g.at(r, c), expected[r][c]) << r << "," << c;
      EXPECT_EQ(g.OccupiedAt(c + 0.5, r + 0.5), expected[r][c] == 1);
    }
  EXPECT_EQ(g.CountOccupied(), 15);
  // No size check with 0; CRLF line ends and blank lines are accepted.
  WriteText(dir.File("crlf.txt"), "\r\n[[0 1]\r\n\r\n [1 1]]\r\n");
  const BinaryGrid h = ReadOccTrajMap(dir.File("crlf.txt"));
  EXPECT_EQ(h.width, 2);
  EXPECT_EQ(h.height, 2);
  EXPECT_EQ(h.cells, (std::vector<std::uint8_t>{0, 1, 1, 1}));
}

TEST(OccTrajMap, ErrorsNameTheFileAndTheLine) {
  TempDir dir;
  const auto expect = [&](const std::string& name, const std::string& text,
                          const std::vector<std::string>& parts, int w = 0, int h = 0) {
    const std::string path = dir.File(name);
    WriteText(path, text);
    std::vector<std::string> all = parts;
    all.push_back(path);
    ExpectErrorContains([&] { ReadOccTrajMap(path, w, h); }, all);
  };
  expect("ragged.txt", "[[1 1 1]\n [1 0]\n [1 1 1]]", {":2:", "ragged", "2 entries", "expected 3"});
  expect("value.txt", "[[1 1 1]\n [1 0 1]\n [1 2 1]]", {":3:", "entry 2", "'2'", "0 or 1"});
  expect("float.txt", "[[1. 1. 1.]]", {":1:", "'1.'", "0 or 1"});
  expect("width.txt", kSmallMap, {":1:", "5 entries", "width 40"}, 40, 4);
  expect("height.txt", kSmallMap, {":4:", "4 rows", "height 40"}, 5, 40);
  expect("empty.txt", "", {":1:", "no map rows"});
  expect("brackets.txt", "[[]]\n\n", {":2:", "no map rows"});
  ExpectErrorContains([&] { ReadOccTrajMap(dir.File("missing.txt")); },
                      {dir.File("missing.txt"), "cannot open"});
}

// ------------------------------------------------------------------------------------------
// Trajectories written here (on the small map: free cells (1,1) (1,2) (1,3) (2,1) (2,3)).

BinaryGrid SmallMap(const TempDir& dir) {
  WriteText(dir.File("small_map.txt"), kSmallMap);
  return ReadOccTrajMap(dir.File("small_map.txt"), 5, 4);
}

TEST(OccTrajTrajectories, ReadsBlocksExactly) {
  TempDir dir;
  const BinaryGrid map = SmallMap(dir);
  WriteText(dir.File("t.txt"),
            "traj-0:\n"
            " 1.50  2.25  3.90\n"
            " 1.10  1.20  2.95\n"
            "\n"
            "traj-1:\r\n"
            "3.5 1.5\r\n"
            "1.5 2.5\r\n");
  ReadReport report;
  const std::vector<Eigen::MatrixX2d> t =
      ReadOccTrajTrajectories(dir.File("t.txt"), map, BadWaypointPolicy::kError, &report);
  ASSERT_EQ(t.size(), 2u);
  Eigen::MatrixX2d t0(3, 2), t1(2, 2);
  t0 << 1.5, 1.1, 2.25, 1.2, 3.9, 2.95;
  t1 << 3.5, 1.5, 1.5, 2.5;
  EXPECT_EQ(t[0], t0);
  EXPECT_EQ(t[1], t1);
  EXPECT_EQ(report.trajectories, 2);
  EXPECT_EQ(report.kept, 2);
  // A null report is allowed; an empty file has no trajectories.
  WriteText(dir.File("empty.txt"), "");
  EXPECT_TRUE(
      ReadOccTrajTrajectories(dir.File("empty.txt"), map, BadWaypointPolicy::kError, nullptr)
          .empty());
}

TEST(OccTrajTrajectories, FormatErrorsNameTheFileAndTheLine) {
  TempDir dir;
  const BinaryGrid map = SmallMap(dir);
  const std::string good = "traj-0:\n1.5 2.5\n1.5 1.5\n";
  const auto expect = [&](const std::string& name, const std::string& text,
                          const std::vector<std::string>& parts) {
    const std::string path = dir.File(name);
    WriteText(path, text);
    std::vector<std::string> all = parts;
    all.push_back(path);
    for (BadWaypointPolicy policy : {BadWaypointPolicy::kError, BadWaypointPolicy::kDrop})
      ExpectErrorContains([&] { ReadOccTrajTrajectories(path, map, policy, nullptr); }, all);
  };
  expect("mismatch.txt", good + "traj-1:\n1.5 2.5 3.5\n1.5 1.5\n",
         {":6:", "traj-1:", "3 x values", "line 5", "2 y values"});
  expect("header.txt", good + "trajectory-1:\n1.5\n1.5\n", {":4:", "'trajectory-1:'", "traj-<k>:"});
  expect("header_k.txt", "traj-a:\n1.5\n1.5\n", {":1:", "'traj-a:'"});
  expect("nan_header.txt", "1.5 2.5\n1.5 1.5\n", {":1:", "'1.5 2.5'", "traj-<k>:"});
  expect("number.txt", good + "traj-1:\n1.5 2.5x\n1.5 1.5\n",
         {":5:", "x value 2", "not a number", "'2.5x'"});
  expect("nan.txt", good + "traj-1:\n1.5 2.5\n1.5 nan\n", {":6:", "y value 2", "not finite"});
  expect("inf.txt", "traj-0:\ninf 2.5\n1.5 1.5\n", {":2:", "x value 1", "not finite", "'inf'"});
  expect("huge.txt", "traj-0:\n1e999 2.5\n1.5 1.5\n", {":2:", "not a number", "'1e999'"});
  expect("eof_x.txt", good + "traj-1:\n", {":4:", "truncated", "traj-1:", "no x line"});
  expect("eof_y.txt", good + "traj-1:\n1.5 2.5\n", {":5:", "truncated", "no y line"});
  expect("header_y.txt", "traj-0:\n1.5 2.5\ntraj-1:\n1.5 2.5\n1.5 1.5\n",
         {":3:", "truncated", "traj-0:", "no y line", "found 'traj-1:'"});
  ExpectErrorContains(
      [&] {
        ReadOccTrajTrajectories(dir.File("missing.txt"), map, BadWaypointPolicy::kDrop, nullptr);
      },
      {dir.File("missing.txt"), "cannot open"});
}

// Blocks: kept, outside (x = 5.2), outside (y < 0), occupied (cell (2, 2)), one waypoint, no
// waypoints, kept.
constexpr const char* kMixedTrajectories =
    "traj-0:\n1.5 3.5\n1.5 1.5\n"
    "traj-1:\n1.5 5.2\n1.5 1.5\n"
    "traj-2:\n1.5 1.5\n-0.1 1.5\n"
    "traj-3:\n1.5 2.5 3.5\n1.5 2.5 1.5\n"
    "traj-4:\n1.5\n1.5\n"
    "traj-5:\n\n\n"
    "traj-6:\n3.5 3.5\n1.5 2.5\n";

TEST(OccTrajTrajectories, DropPolicyCountsEveryDroppedTrajectory) {
  TempDir dir;
  const BinaryGrid map = SmallMap(dir);
  WriteText(dir.File("mixed.txt"), kMixedTrajectories);
  ReadReport report;
  const std::vector<Eigen::MatrixX2d> t =
      ReadOccTrajTrajectories(dir.File("mixed.txt"), map, BadWaypointPolicy::kDrop, &report);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0](1, 0), 3.5);
  EXPECT_EQ(t[1](1, 1), 2.5);
  EXPECT_EQ(report.trajectories, 7);
  EXPECT_EQ(report.kept, 2);
  EXPECT_EQ(report.dropped_outside, 2);
  EXPECT_EQ(report.dropped_occupied, 1);
  EXPECT_EQ(report.dropped_too_short, 2);
  // Add sums field by field.
  ReadReport sum = report;
  sum.Add(report);
  EXPECT_EQ(sum.trajectories, 14);
  EXPECT_EQ(sum.kept, 4);
  EXPECT_EQ(sum.dropped_outside, 4);
  EXPECT_EQ(sum.dropped_occupied, 2);
  EXPECT_EQ(sum.dropped_too_short, 4);
}

TEST(OccTrajTrajectories, ErrorPolicyNamesTheBadWaypoint) {
  TempDir dir;
  const BinaryGrid map = SmallMap(dir);
  const std::string ok = "traj-0:\n1.5 3.5\n1.5 1.5\n";
  const auto expect = [&](const std::string& name, const std::string& block,
                          const std::vector<std::string>& parts) {
    const std::string path = dir.File(name);
    WriteText(path, ok + block);
    std::vector<std::string> all = parts;
    all.push_back(path);
    ExpectErrorContains(
        [&] { ReadOccTrajTrajectories(path, map, BadWaypointPolicy::kError, nullptr); }, all);
  };
  expect("outside.txt", "traj-1:\n1.5 5.2\n1.5 1.5\n",
         {":5:", "traj-1:", "waypoint 2", "x=5.2", "outside the 5 x 4 map"});
  expect("negative.txt", "traj-1:\n1.5 1.5\n-0.1 1.5\n",
         {":5:", "waypoint 1", "y=-0.1", "outside"});
  expect("occupied.txt", "traj-1:\n1.5 2.5 3.5\n1.5 2.5 1.5\n",
         {":5:", "waypoint 2", "occupied cell (row 2, column 2)"});
  expect("short.txt", "traj-1:\n1.5\n1.5\n", {":5:", "1 waypoint", "fewer than 2"});
  expect("none.txt", "traj-1:\n\n\n", {":5:", "0 waypoint", "fewer than 2"});
}

// ------------------------------------------------------------------------------------------
// Map lists and whole maps.

TEST(OccTrajList, ReadsIdsInFileOrderAndRejectsBadLists) {
  TempDir dir;
  WriteText(dir.File("train_maps.txt"), "bbb\n\naaa  \r\nccc\n");
  EXPECT_EQ(ListOccTrajMaps(dir.path()), (std::vector<std::string>{"bbb", "aaa", "ccc"}));
  const std::string list = dir.File("train_maps.txt");
  WriteText(list, "\n\n");
  ExpectErrorContains([&] { ListOccTrajMaps(dir.path()); }, {list, "no map ids"});
  WriteText(list, "aaa\nbbb\naaa\n");
  ExpectErrorContains([&] { ListOccTrajMaps(dir.path()); }, {list + ":3:", "duplicate", "'aaa'"});
  WriteText(list, "aaa\nbbb ccc\n");
  ExpectErrorContains([&] { ListOccTrajMaps(dir.path()); }, {list + ":2:", "one map id"});
  WriteText(list, "../x\n");
  ExpectErrorContains([&] { ListOccTrajMaps(dir.path()); }, {list + ":1:", "'../x'"});
  TempDir empty;
  ExpectErrorContains([&] { ListOccTrajMaps(empty.path()); },
                      {empty.File("train_maps.txt"), "cannot open"});
}

TEST(OccTrajLoad, ReadsMapAndTrajectoriesOfAnId) {
  TempDir dir;
  std::filesystem::create_directories(dir.File("maps"));
  std::filesystem::create_directories(dir.File("trajs"));
  // The small map with a fifth wall row: 5 x 5.
  std::string square = kSmallMap;
  square.pop_back();
  square += "\n [1 1 1 1 1]]";
  WriteText(dir.File("maps/occtraj_abc_map.txt"), square);
  WriteText(dir.File("trajs/occtraj_abc_trajs.txt"), kMixedTrajectories);
  ReadReport report;
  const MapTrajectories m = LoadOccTrajMap(dir.path(), "abc", 5, BadWaypointPolicy::kDrop, &report);
  EXPECT_EQ(m.id, "abc");
  EXPECT_EQ(m.map.width, 5);
  EXPECT_EQ(m.map.height, 5);
  ASSERT_EQ(m.trajectories.size(), 2u);
  EXPECT_EQ(m.trajectories[1](1, 1), 2.5);
  EXPECT_EQ(report.trajectories, 7);
  EXPECT_EQ(report.dropped_outside, 2);
  ExpectErrorContains(
      [&] { LoadOccTrajMap(dir.path(), "abc", 5, BadWaypointPolicy::kError, nullptr); },
      {"occtraj_abc_trajs.txt:5:", "traj-1:", "outside"});
  ExpectErrorContains(
      [&] { LoadOccTrajMap(dir.path(), "abc", 40, BadWaypointPolicy::kDrop, nullptr); },
      {"occtraj_abc_map.txt:1:", "width 40"});
  // A 5 x 4 map is not 5 x 5.
  WriteText(dir.File("maps/occtraj_def_map.txt"), kSmallMap);
  ExpectErrorContains(
      [&] { LoadOccTrajMap(dir.path(), "def", 5, BadWaypointPolicy::kDrop, nullptr); },
      {"occtraj_def_map.txt:4:", "4 rows", "height 5"});
  ExpectErrorContains(
      [&] { LoadOccTrajMap(dir.path(), "abc", 0, BadWaypointPolicy::kDrop, nullptr); },
      {"map_size", "got 0", "'abc'"});
  ExpectErrorContains(
      [&] { LoadOccTrajMap(dir.path(), "xyz", 5, BadWaypointPolicy::kDrop, nullptr); },
      {"occtraj_xyz_map.txt", "cannot open"});
  // The map is read before the trajectories: a missing trajectory file is reported as such.
  WriteText(dir.File("maps/occtraj_ghi_map.txt"), square);
  ExpectErrorContains(
      [&] { LoadOccTrajMap(dir.path(), "ghi", 5, BadWaypointPolicy::kDrop, nullptr); },
      {"occtraj_ghi_trajs.txt", "cannot open"});
}

// ------------------------------------------------------------------------------------------
// Splits.

std::vector<std::string> Ids(int n) {
  std::vector<std::string> ids;
  for (int i = 0; i < n; ++i) ids.push_back("map" + std::to_string(1000 + i));
  return ids;
}

TEST(SplitMaps, IsADeterministicSortedPartitionWithRoundedSizes) {
  std::vector<std::string> ids = Ids(368);
  const MapSplit a = SplitMaps(ids, 0.1, 0.2, 7);
  EXPECT_EQ(a.test.size(), 74u);  // round(73.6)
  EXPECT_EQ(a.val.size(), 37u);   // round(36.8)
  EXPECT_EQ(a.train.size(), 257u);
  for (const auto* part : {&a.train, &a.val, &a.test})
    EXPECT_TRUE(std::is_sorted(part->begin(), part->end()));
  std::vector<std::string> all;
  for (const auto* part : {&a.train, &a.val, &a.test})
    all.insert(all.end(), part->begin(), part->end());
  std::sort(all.begin(), all.end());
  EXPECT_EQ(all, ids);  // disjoint (same size, no repeats) and covering
  // The input order does not matter (ids are sorted first); the seed does.
  std::reverse(ids.begin(), ids.end());
  const MapSplit b = SplitMaps(ids, 0.1, 0.2, 7);
  EXPECT_EQ(a.train, b.train);
  EXPECT_EQ(a.val, b.val);
  EXPECT_EQ(a.test, b.test);
  const MapSplit c = SplitMaps(ids, 0.1, 0.2, 8);
  EXPECT_NE(a.test, c.test);
  // Halves round away from zero: 10 * 0.25 = 2.5 -> 3.
  const MapSplit d = SplitMaps(Ids(10), 0.25, 0.25, 1);
  EXPECT_EQ(d.val.size(), 3u);
  EXPECT_EQ(d.test.size(), 3u);
  EXPECT_EQ(d.train.size(), 4u);
}

TEST(SplitMaps, MatchesAnIndependentComputationOfTheShuffle) {
  // Computed outside this code base (a Python mt19937_64 checked against the standard's 10000th
  // output, and the Fisher-Yates of occ_traj.cc: for i = n-1..1, swap i with r % (i + 1), r
  // redrawn while r >= 2^64-1 - (2^64-1) % (i + 1)). std::mt19937_64's sequence is fixed by the
  // standard, so this split holds on every machine.
  const MapSplit s = SplitMaps(Ids(8), 0.25, 0.25, 42);
  EXPECT_EQ(s.test, (std::vector<std::string>{"map1000", "map1007"}));
  EXPECT_EQ(s.val, (std::vector<std::string>{"map1001", "map1005"}));
  EXPECT_EQ(s.train, (std::vector<std::string>{"map1002", "map1003", "map1004", "map1006"}));
}

TEST(SplitMaps, PlacesEveryIdUniformlyOverSeeds) {
  // Monte Carlo: with 2 of 10 ids in test, each id is in test with probability 0.2. Over 4000
  // seeds the frequency has std 0.0063; 0.03 is about 4.7 std.
  const std::vector<std::string> ids = Ids(10);
  std::map<std::string, int> in_test, in_val;
  constexpr int kSeeds = 4000;
  for (int seed = 0; seed < kSeeds; ++seed) {
    const MapSplit s = SplitMaps(ids, 0.2, 0.2, static_cast<std::uint64_t>(seed));
    for (const std::string& id : s.test) ++in_test[id];
    for (const std::string& id : s.val) ++in_val[id];
  }
  for (const std::string& id : ids) {
    EXPECT_NEAR(in_test[id] / static_cast<double>(kSeeds), 0.2, 0.03) << id;
    EXPECT_NEAR(in_val[id] / static_cast<double>(kSeeds), 0.2, 0.03) << id;
  }
}

TEST(SplitMaps, RejectsBadFractionsEmptyPartsAndDuplicates) {
  const std::vector<std::string> ids = Ids(20);
  ExpectErrorContains([&] { SplitMaps(ids, -0.1, 0.2, 0); }, {"val_fraction", "-0.1", "[0, 1)"});
  ExpectErrorContains([&] { SplitMaps(ids, 1.0, 0.2, 0); }, {"val_fraction", "[0, 1)"});
  ExpectErrorContains([&] { SplitMaps(ids, 0.2, 1.5, 0); }, {"test_fraction", "1.5"});
  ExpectErrorContains([&] { SplitMaps(ids, 0.2, std::nan(""), 0); }, {"test_fraction", "nan"});
  ExpectErrorContains([&] { SplitMaps(ids, 0.5, 0.5, 0); }, {"must be < 1"});
  ExpectErrorContains([&] { SplitMaps(ids, 0.0, 0.2, 0); }, {"0 val", "non-empty"});
  ExpectErrorContains([&] { SplitMaps(Ids(3), 0.1, 0.4, 0); }, {"0 val", "non-empty"});
  ExpectErrorContains([&] { SplitMaps(Ids(4), 0.4, 0.4, 0); }, {"0 train", "non-empty"});
  ExpectErrorContains([&] { SplitMaps({}, 0.2, 0.2, 0); }, {"0 maps"});
  std::vector<std::string> dup = ids;
  dup.push_back("map1003");
  ExpectErrorContains([&] { SplitMaps(dup, 0.2, 0.2, 0); }, {"duplicate", "'map1003'"});
}

}  // namespace
}  // namespace foresight::otnet
