#include "datasets/crowd_replay.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "tests/test_util.h"

namespace foresight {
namespace {

/// $FORESIGHT_DATA or ../shared/data when `relative` exists under it, else "".
std::string DataRootWith(const std::string& relative) {
  std::vector<std::filesystem::path> roots;
  if (const char* data = std::getenv("FORESIGHT_DATA")) roots.emplace_back(data);
  if (const std::string shared = testing::SharedDataDir(); !shared.empty())
    roots.emplace_back(shared);
  for (const auto& root : roots)
    if (std::filesystem::exists(root / relative)) return root.string();
  return "";
}

TEST(CrowdReplay, ReadsThorTrackletsSortedByTime) {
  testing::TempDir dir;
  const std::string path = dir.File("thor.csv");
  testing::WriteText(
      path,
      "0.43,12001,1.0,2.0,0.1,0.0\n0.02,12001,0.5,2.0,0.1,0.0\n0.10,12002,-1,-1,0.0,0.0\n"
      "\n0.84,12001,1.5,2.5,0.1,0.785\n0.51,12002,-1.2,-1,0.5,3.142\n");
  const TrackSet set = ReadThorTracks(path);
  ASSERT_EQ(set.tracks.size(), 2u);
  const Track& a = set.tracks[0];
  EXPECT_EQ(a.agent_id, 12001);
  EXPECT_EQ(a.time, (std::vector<double>{0.02, 0.43, 0.84}));
  EXPECT_DOUBLE_EQ(a.positions(0, 0), 0.5);
  EXPECT_DOUBLE_EQ(a.positions(2, 1), 2.5);
  EXPECT_EQ(set.tracks[1].agent_id, 12002);
  EXPECT_EQ(set.tracks[1].size(), 2);
}

TEST(CrowdReplay, BadThorInputNamesFileAndLine) {
  testing::TempDir dir;
  const std::string path = dir.File("bad.csv");
  testing::WriteText(path, "0.02,12001,0.5,2.0,0.1,0.0\n0.43,12001,nan,2.0,0.1,0.0\n");
  testing::ExpectErrorContains([&] { ReadThorTracks(path); }, {path + ":2", "x", "'nan'"});
  testing::WriteText(path, "0.02,12001,0.5,2.0,0.1\n");
  testing::ExpectErrorContains([&] { ReadThorTracks(path); }, {path + ":1", "6 comma-separated"});
  testing::WriteText(path, "0.02,12001,0.5,2.0,0.1,0\n0.02,12001,0.6,2.0,0.1,0\n");
  testing::ExpectErrorContains([&] { ReadThorTracks(path); }, {path + ":2", "two samples"});
  testing::WriteText(path, "0.02,abc,0.5,2.0,0.1,0\n");
  testing::ExpectErrorContains([&] { ReadThorTracks(path); }, {path + ":1", "person_id", "'abc'"});
  testing::ExpectErrorContains([&] { ReadThorTracks(dir.File("missing.csv")); },
                               {"missing.csv", "cannot open"});
}

TEST(CrowdReplay, ReadsEthObsmatWithYInTheFifthColumnAndInferredFrameStep) {
  testing::TempDir dir;
  const std::string path = dir.File("obsmat.txt");
  // frame id x z y vx vz vy; frames every 6 -> 0.4 s.
  testing::WriteText(path,
                     "   7.8000000e+02   1.0000000e+00   8.0e+00   0.0e+00   3.0e+00   1.0 0 0\n"
                     "   7.8600000e+02   1.0000000e+00   8.5e+00   0.0e+00   3.25e+00   1.0 0 0\n"
                     "   7.8600000e+02   2.0000000e+00   1.0e+00   0.0e+00   -1.0e+00   1.0 0 0\n"
                     "   7.9200000e+02   1.0000000e+00   9.0e+00   0.0e+00   3.5e+00   1.0 0 0\n"
                     "   7.9200000e+02   2.0000000e+00   1.5e+00   0.0e+00   -1.0e+00   1.0 0 0\n");
  const TrackSet set = ReadEthObsmat(path);
  ASSERT_EQ(set.tracks.size(), 2u);
  EXPECT_NEAR(set.tracks[0].time[1] - set.tracks[0].time[0], 0.4, 1e-12);
  EXPECT_NEAR(set.tracks[0].time[0], 780 * 0.4 / 6, 1e-9);
  EXPECT_DOUBLE_EQ(set.tracks[0].positions(1, 1), 3.25);  // pos_y, not pos_z
  EXPECT_DOUBLE_EQ(set.tracks[1].positions(0, 0), 1.0);
  testing::WriteText(path, "780 1 8 0 3 1 0\n");
  testing::ExpectErrorContains([&] { ReadEthObsmat(path); }, {path + ":1", "8 fields"});
  testing::WriteText(path, "780 1 8 0 inf 1 0 0\n");
  testing::ExpectErrorContains([&] { ReadEthObsmat(path); }, {path + ":1", "pos_y", "'inf'"});
}

// Found by fuzz_crowd_replay (tests/fuzz/corpus/crowd_replay/regress_huge_frame): integral but
// huge frames and ids overflowed the conversions to integers (undefined behaviour).
TEST(CrowdReplay, HugeFramesAndIdsAreErrors) {
  testing::TempDir dir;
  const std::string path = dir.File("huge.txt");
  testing::WriteText(path, "780 1 8 0 3 1 0 0\n7.92e+82 1 8.5 0 3.25 1 0 0\n");
  testing::ExpectErrorContains([&] { ReadEthObsmat(path); },
                               {path + ":2", "frame '7.92e+82'", "[-2^53, 2^53]"});
  testing::WriteText(path, "780 1 8 0 3 1 0 0\n786 -1e19 8.5 0 3.25 1 0 0\n");
  testing::ExpectErrorContains([&] { ReadEthObsmat(path); }, {path + ":2", "ped_id '-1e19'"});
  testing::WriteText(path, "0.02,12001,0.5,2.0,0.1,0.0\n0.43,1e30,1.0,2.0,0.1,0.0\n");
  testing::ExpectErrorContains([&] { ReadThorTracks(path); },
                               {path + ":2", "person_id '1e30'", "[-2^53, 2^53]"});
}

TEST(CrowdReplay, ResamplingInterpolatesOnTheGridWithoutExtrapolationAndSplitsGaps) {
  TrackSet raw;
  Track tr;
  tr.agent_id = 5;
  tr.time = {0.02, 0.43, 0.84, 3.0, 3.41};  // a 2.16 s gap after 0.84
  tr.positions.resize(5, 2);
  for (int i = 0; i < 5; ++i)
    tr.positions.row(i) << 1.0 + 2.0 * tr.time[i], -0.5 * tr.time[i];  // linear
  raw.tracks.push_back(tr);
  const TrackSet out = ResampleTracks(raw, 0.1, 1.0);
  EXPECT_DOUBLE_EQ(out.seconds_per_step, 0.1);
  ASSERT_EQ(out.tracks.size(), 2u);
  const Track& a = out.tracks[0];
  ASSERT_EQ(a.size(), 8);  // 0.1 ... 0.8 inside [0.02, 0.84]
  EXPECT_NEAR(a.time.front(), 0.1, 1e-12);
  EXPECT_NEAR(a.time.back(), 0.8, 1e-12);
  for (int i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a.positions(i, 0), 1.0 + 2.0 * a.time[i], 1e-12);
    EXPECT_NEAR(a.positions(i, 1), -0.5 * a.time[i], 1e-12);
  }
  EXPECT_EQ(out.tracks[1].size(), 5);  // 3.0 ... 3.4 inside [3.0, 3.41]
  EXPECT_EQ(out.tracks[1].agent_id, 5);
}

TrackSet LinearTracks() {
  // Track i starts at time 10 i and walks +x at 1 m/s for 20 s on the 0.1 s grid.
  TrackSet set;
  set.source = "test";
  set.seconds_per_step = 0.1;
  for (int i = 0; i < 10; ++i) {
    Track tr;
    tr.agent_id = 100 + i;
    tr.positions.resize(201, 2);
    for (int k = 0; k <= 200; ++k) {
      tr.time.push_back(10.0 * i + 0.1 * k);
      tr.positions.row(k) << 0.1 * k, static_cast<double>(i);
    }
    set.tracks.push_back(tr);
  }
  return set;  // spans [0, 110] s
}

TEST(CrowdReplay, OverlaidWindowsStartAtZeroAndAgentsAreActiveWhileCovered) {
  ReplayConfig rc;
  rc.step = 0.1;
  rc.overlays = 3;
  rc.overlay_spacing = 25;
  rc.duration = 30;
  ReplayCrowd crowd(LinearTracks(), rc, 0.4, 5);
  ASSERT_EQ(crowd.window_starts().size(), 3u);
  std::set<std::int64_t> ids;
  for (const auto& a : crowd.agents()) ids.insert(a.id);
  EXPECT_EQ(ids.size(), crowd.agents().size());
  EXPECT_GT(crowd.agents().size(), 6u);  // each 30 s window holds parts of 3-4 tracks
  const RobotAgent robot;
  int max_active = 0;
  for (int k = 0; k < 350; ++k) {
    int active = 0;
    for (const auto& a : crowd.agents()) {
      if (!a.active) continue;
      ++active;
      EXPECT_NEAR(a.velocity.x(), 1.0, 1e-9);
      EXPECT_NEAR(a.velocity.y(), 0.0, 1e-9);
      EXPECT_NEAR(a.radius, 0.4, 0);
      // x = (recording time - track start), y = track index: check against the window's start.
      const double y = a.position.y();
      bool consistent = false;
      for (double s : crowd.window_starts())
        consistent = consistent || std::abs(a.position.x() - (s + crowd.time() - 10.0 * y)) < 1e-6;
      EXPECT_TRUE(consistent) << "agent " << a.id << " at t = " << crowd.time();
    }
    max_active = std::max(max_active, active);
    if (crowd.time() > rc.duration + 1e-9) {
      EXPECT_EQ(active, 0);
    }
    crowd.Step(0.1, robot);
  }
  EXPECT_GE(max_active, 3);
  // The seed moves the windows.
  ReplayCrowd other(LinearTracks(), rc, 0.4, 6);
  EXPECT_NE(other.window_starts()[0], crowd.window_starts()[0]);
  ReplayCrowd same(LinearTracks(), rc, 0.4, 5);
  EXPECT_EQ(same.window_starts(), crowd.window_starts());
  rc.duration = 200;
  testing::ExpectErrorContains([&] { ReplayCrowd c(LinearTracks(), rc, 0.4, 1); },
                               {"shorter than replay.duration"});
}

TEST(CrowdReplay, ThorMapRasterUsesTheReadmeMapping) {
  testing::TempDir dir;
  const std::string png = dir.File("map.png");
  // 0.01 m/px from (x, y) = (-11, 13.5): 400 x 300 px covers x in [-11, -8], y in [9.5, 13.5].
  cv::Mat img(400, 300, CV_8UC4, cv::Scalar(255, 255, 255, 255));
  img(cv::Rect(100, 200, 50, 50))
      .setTo(cv::Scalar(0, 0, 0, 255));  // x in [-10, -9.5], y in [11, 11.5]
  ASSERT_TRUE(cv::imwrite(png, img));
  const OccupancyRaster r = ThorMapRaster(png, Eigen::Vector4d(-11, -7, 9.5, 13.5), 0.1);
  EXPECT_EQ(r.cells.rows(), 40);
  EXPECT_EQ(r.cells.cols(), 40);
  EXPECT_TRUE(r.Occupied(-9.75, 11.25));
  EXPECT_FALSE(r.Occupied(-10.25, 11.25));
  EXPECT_FALSE(r.Occupied(-9.75, 11.75));
  EXPECT_TRUE(r.Occupied(-7.5, 11.0));   // beyond the image
  EXPECT_TRUE(r.Occupied(-12.0, 11.0));  // beyond the raster
  testing::ExpectErrorContains(
      [&] { ThorMapRaster(dir.File("none.png"), Eigen::Vector4d(0, 1, 0, 1), 0.1); },
      {"none.png", "not found"});
}

TEST(CrowdReplay, EthMapRasterMapsObstaclePixelsThroughTheHomography) {
  testing::TempDir dir;
  const std::string png = dir.File("map.png");
  cv::Mat img(100, 200, CV_8UC1, cv::Scalar(0));  // black = free in ETH maps
  img.row(50).setTo(cv::Scalar(255));             // a white line = obstacle
  ASSERT_TRUE(cv::imwrite(png, img));
  // world x = 0.05 col - 1, world y = -0.05 row + 4  (H maps [row, col, 1] to [x, y, 1]).
  Eigen::Matrix3d H;
  H << 0, 0.05, -1, -0.05, 0, 4, 0, 0, 1;
  const OccupancyRaster r = EthMapRaster(png, H, Eigen::Vector4d(-1, 9, -3, 4), 0.1);
  // Row 50 -> y in (1.475, 1.5]: every cell along x in [-1, 9) at that y is occupied.
  int occupied_on_line = 0;
  for (double x = -0.95; x < 9; x += 0.1) occupied_on_line += r.Occupied(x, 1.48);
  EXPECT_EQ(occupied_on_line, 100);
  EXPECT_FALSE(r.Occupied(2.0, 2.5));
  EXPECT_FALSE(r.Occupied(2.0, 0.5));
  EXPECT_FALSE(r.Occupied(2.0, -0.5));
  EXPECT_TRUE(r.Occupied(2.0, -2.0));  // y < -1: beyond the image's last row
}

TEST(CrowdReplay, RealThorRunReplaysOnFreeSpaceAtWalkingSpeed) {
  const std::string root = DataRootWith("thor/thor1_exp-1-run-2.csv");
  if (root.empty())
    GTEST_SKIP() << "thor/thor1_exp-1-run-2.csv not found under $FORESIGHT_DATA or ../shared/data";
  const TrackSet raw = ReadThorTracks(root + "/thor/thor1_exp-1-run-2.csv");
  EXPECT_EQ(raw.tracks.size(), 87u);  // README
  CrowdScenarioConfig s = DatasetScenario();
  s.replay.root = root;
  const std::unique_ptr<Crowd> crowd_ptr = MakeCrowd(s, 1);
  Crowd& crowd = *crowd_ptr;
  const OccupancyRaster map = ScenarioOccupancy(s, 0.1);
  // The default robot start and goal are free (robot disc with the start jitter).
  const OccupancyRaster fine = ScenarioOccupancy(s, 0.05);
  for (const auto& pt : {s.robot_start, s.robot_goal})
    for (double dx = -0.7; dx <= 0.7; dx += 0.05)
      for (double dy = -0.7; dy <= 0.7; dy += 0.05)
        if (std::hypot(dx, dy) <= s.robot_radius + std::sqrt(2.0) * s.start_jitter) {
          EXPECT_FALSE(fine.Occupied(pt[0] + dx, pt[1] + dy)) << pt[0] + dx << ", " << pt[1] + dy;
        }
  int samples = 0, on_free = 0, max_active = 0;
  std::vector<double> speeds;
  for (int k = 0; k < 600; ++k) {
    int active = 0;
    for (const auto& a : crowd.agents()) {
      if (!a.active) continue;
      ++active;
      ++samples;
      on_free += !map.Occupied(a.position.x(), a.position.y());
      speeds.push_back(a.velocity.norm());
    }
    max_active = std::max(max_active, active);
    crowd.Step(0.1, RobotAgent{});
  }
  ASSERT_GT(samples, 1000);
  std::nth_element(speeds.begin(), speeds.begin() + speeds.size() / 2, speeds.end());
  const double median = speeds[speeds.size() / 2];
  EXPECT_GT(static_cast<double>(on_free) / samples, 0.97);
  EXPECT_GT(median, 0.3);
  EXPECT_LT(median, 1.8);
  std::cout << "[ thor1 replay, 3 windows ] max active " << max_active << ", median speed "
            << median << " m/s, on free cells " << 100.0 * on_free / samples << " %\n";
}

TEST(CrowdReplay, RealEthObsmatReplaysOnFreeSpaceAtWalkingSpeed) {
  const std::string root = DataRootWith("eth_ucy/eth_original/seq_eth/obsmat.txt");
  if (root.empty())
    GTEST_SKIP() << "eth_ucy/eth_original/seq_eth/obsmat.txt not found under $FORESIGHT_DATA or "
                    "../shared/data";
  CrowdScenarioConfig s;
  s.name = "dataset";
  s.source = CrowdSource::kReplay;
  s.extent = {-8, 15, -4, 14};
  s.robot_start = {0, 5, 0};
  s.robot_goal = {10, 5};
  s.replay.format = "eth_obsmat";
  s.replay.file = "eth_ucy/eth_original/seq_eth/obsmat.txt";
  s.replay.map_image = "eth_ucy/eth_original/seq_eth/map.png";
  s.replay.root = root;
  ReplayCrowd crowd(s, 2);
  const OccupancyRaster map = ReplayOccupancy(s, 0.1);
  int samples = 0, on_free = 0;
  std::vector<double> speeds;
  for (int k = 0; k < 600; ++k) {
    for (const auto& a : crowd.agents()) {
      if (!a.active) continue;
      ++samples;
      on_free += !map.Occupied(a.position.x(), a.position.y());
      speeds.push_back(a.velocity.norm());
    }
    crowd.Step(0.1, RobotAgent{});
  }
  ASSERT_GT(samples, 1000);
  std::nth_element(speeds.begin(), speeds.begin() + speeds.size() / 2, speeds.end());
  const double median = speeds[speeds.size() / 2];
  EXPECT_GT(static_cast<double>(on_free) / samples, 0.95);
  EXPECT_GT(median, 0.8);  // README: 1.47 m/s median from obsmat
  EXPECT_LT(median, 2.0);
  std::cout << "[ eth obsmat replay, 3 windows ] median speed " << median << " m/s, on free cells "
            << 100.0 * on_free / samples << " %\n";
}

}  // namespace
}  // namespace foresight
