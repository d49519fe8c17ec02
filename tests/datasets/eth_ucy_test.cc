#include "datasets/eth_ucy.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "tests/test_util.h"

namespace foresight {
namespace {

TEST(EthUcy, ReadsTracksAndSplitsAtGaps) {
  testing::TempDir dir;
  const std::string path = dir.File("scene.txt");
  // Pedestrian 1: frames 0..30 then a gap to 60..70 (two tracks); pedestrian 2: 10..20.
  testing::WriteText(
      path,
      "0\t1\t0.0\t0.0\n10\t1\t0.4\t0.0\n10\t2.0\t5.0\t5.0\n20\t1\t0.8\t0.0\n20\t2.0\t5.0\t5.4\n"
      "30\t1\t1.2\t0.0\n60\t1\t2.4\t0.0\n70\t1\t2.8\t0.0\n");
  EthUcyReadStats stats;
  const TrackSet set = ReadEthUcy(path, 0.4, &stats);
  EXPECT_EQ(stats.rows, 8u);
  EXPECT_EQ(stats.pedestrians, 2u);
  EXPECT_EQ(stats.frame_step, 10);
  EXPECT_EQ(stats.gaps_split, 1u);
  ASSERT_EQ(set.tracks.size(), 3u);
  EXPECT_EQ(set.tracks[0].size(), 4);
  EXPECT_NEAR(set.tracks[0].time[3], 1.2, 1e-12);  // frame 30 = 3 steps of 0.4 s
  EXPECT_NEAR(set.tracks[1].time[0], 2.4, 1e-12);
  EXPECT_EQ(set.tracks[2].agent_id, 2);
}

TEST(EthUcy, MalformedInputNamesFileAndLine) {
  testing::TempDir dir;
  auto check = [&](const std::string& text, std::vector<std::string> parts) {
    const std::string path = dir.File("bad.txt");
    testing::WriteText(path, text);
    parts.insert(parts.begin(), path);
    testing::ExpectErrorContains([&] { ReadEthUcy(path, 0.4); }, parts);
  };
  check("0\t1\t0.0\t0.0\n10\t1\tabc\t0.0\n", {":2:", "column 'x'", "'abc'"});
  check("0\t1\t0.0\n", {":1:", "expected 4 columns", "got 3"});
  check("0\t1\t0.0\t0.0\n10\t1\tnan\t0.0\n", {":2:", "not finite"});
  check("10\t1\t0.0\t0.0\n0\t2\t1.0\t0.0\n", {":2:", "not sorted"});
  check("0\t1\t0.0\t0.0\n0\t1\t1.0\t0.0\n", {"pedestrian 1", "twice in frame 0"});
  check("", {"no observations"});
  check("0\t1.5\t0.0\t0.0\n", {":1:", "ped_id is not an integer"});
  testing::ExpectErrorContains([] { ReadEthUcy("/nonexistent/eth.txt", 0.4); },
                               {"/nonexistent/eth.txt"});
}

// Found by fuzz_eth_ucy (tests/fuzz/corpus/eth_ucy/regress_huge_ped_id): an integral but huge
// ped_id or frame_id overflowed the conversion to an integer (undefined behaviour).
TEST(EthUcy, HugeIdsAndFramesAreErrors) {
  testing::TempDir dir;
  const std::string path = dir.File("huge.txt");
  testing::WriteText(path, "0 1 0 0\n6 2.00e+40 1 1\n");
  testing::ExpectErrorContains([&] { ReadEthUcy(path, 0.4); },
                               {path + ":2:", "ped_id", "'2.00e+40'", "[-2^53, 2^53]"});
  testing::WriteText(path, "0 1 0 0\n1e300 1 1 1\n");
  testing::ExpectErrorContains([&] { ReadEthUcy(path, 0.4); },
                               {path + ":2:", "frame_id", "'1e300'", "[-2^53, 2^53]"});
}

TEST(EthUcy, ReadsEveryRealSceneWhenPresent) {
  const std::string data = testing::SharedDataDir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: skipping the real ETH/UCY files";
  const auto dir = std::filesystem::path(data) / "eth_ucy" / "all_data";
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EthUcyReadStats stats;
    const TrackSet set = ReadEthUcy(entry.path().string(), 0.4, &stats);
    EXPECT_EQ(stats.frame_step, 10) << entry.path();
    EXPECT_GT(set.tracks.size(), 50u) << entry.path();
    EXPECT_EQ(set.NumPoints(), stats.rows) << "no observation is dropped: " << entry.path();
    ++files;
  }
  EXPECT_GE(files, 7u);
}

}  // namespace
}  // namespace foresight
