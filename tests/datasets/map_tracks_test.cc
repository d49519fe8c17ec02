// Scenes with maps for constrained prediction (thesis ch 7). Without data: the Occ-Traj120 raster
// orientation against BinaryGrid::OccupiedAt (every 0.01 point, cell boundaries included), the
// report's counts on a hand-made scene and on hand-written Occ-Traj120 files, config and
// missing-file errors, split determinism and disjointness (by scene, by track), the synthetic
// generator (determinism, free samples, speed, curving around obstacles against a
// constant-velocity extrapolation). With ../shared/data (skipped otherwise): THOR, ETH and
// Occ-Traj120 load with > 95 % (Occ-Traj120: all) samples on free cells.

#include "datasets/map_tracks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <set>
#include <sstream>

#include "tests/test_util.h"

namespace foresight {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::TempDir;
using foresight::testing::WriteText;

Track MakeTrack(std::int64_t id, const std::vector<Eigen::Vector2d>& points) {
  Track t;
  t.agent_id = id;
  t.positions.resize(static_cast<Eigen::Index>(points.size()), 2);
  for (std::size_t i = 0; i < points.size(); ++i) {
    t.positions.row(static_cast<Eigen::Index>(i)) = points[i];
    t.time.push_back(0.4 * static_cast<double>(i));
  }
  return t;
}

/// `n` points from (x0, y0) in steps of (dx, dy).
std::vector<Eigen::Vector2d> Line(double x0, double y0, double dx, double dy, int n) {
  std::vector<Eigen::Vector2d> p;
  for (int i = 0; i < n; ++i) p.emplace_back(x0 + i * dx, y0 + i * dy);
  return p;
}

// ------------------------------------------------------------------------------------------
// Occ-Traj120 raster orientation.

TEST(MapTracks, OccTrajRasterMatchesBinaryGridEverywhereIncludingCellBoundaries) {
  BinaryGrid grid(5, 4);  // x in [0, 5), y in [0, 4)
  grid.at(3, 1) = 1;      // y in [3, 4), x in [1, 2): the top row of the map
  grid.at(0, 4) = 1;      // y in [0, 1), x in [4, 5): the bottom right corner
  grid.at(2, 2) = 1;
  for (int sub : {1, 10}) {
    const OccupancyRaster r = OccTrajRaster(grid, sub);
    ASSERT_EQ(r.cells.rows(), 4 * sub);
    ASSERT_EQ(r.cells.cols(), 5 * sub);
    EXPECT_DOUBLE_EQ(r.resolution, 1.0 / sub);
    // Raster row 0 is y_max: grid row 3 at the top, grid row 0 at the bottom.
    EXPECT_EQ(r.cells(0, 1 * sub), 1);
    EXPECT_EQ(r.cells(3 * sub, 4 * sub), 1);
    EXPECT_EQ(r.cells(0, 4 * sub), 0);
    EXPECT_EQ(r.cells(3 * sub, 1 * sub), 0);
    EXPECT_EQ((r.cells.array() != 0).count(), 3 * sub * sub);
    EXPECT_TRUE(r.Occupied(1.5, 3.5));
    EXPECT_FALSE(r.Occupied(1.5, 0.5));
    // Every point with two decimals (as the data files), boundaries included.
    int mismatches = 0;
    for (int i = 0; i < 500; ++i)
      for (int j = 0; j < 400; ++j) {
        const double x = i / 100.0, y = j / 100.0;
        mismatches += r.Occupied(x, y) != grid.OccupiedAt(x, y);
        mismatches += !InsideRaster(r, x, y);
      }
    EXPECT_EQ(mismatches, 0) << "subdivisions " << sub;
    EXPECT_FALSE(InsideRaster(r, 5.0, 1.0));
    EXPECT_FALSE(InsideRaster(r, 1.0, 4.0));
    EXPECT_FALSE(InsideRaster(r, -0.01, 1.0));
  }
}

TEST(MapTracks, InsideRasterAgreesWithOccupiedOutsideTheExtent) {
  OccupancyRaster r;
  r.extent = Eigen::Vector4d(-2, 3, 1, 4);
  r.resolution = 0.5;
  r.cells.setZero(6, 10);
  for (double x = -3; x <= 4; x += 0.05)
    for (double y = 0; y <= 5; y += 0.05)
      if (!InsideRaster(r, x, y)) {
        EXPECT_TRUE(r.Occupied(x, y)) << x << ", " << y;
      }
  EXPECT_TRUE(InsideRaster(r, -2, 4));  // x_min and y_max are inside
  EXPECT_FALSE(InsideRaster(r, 3, 2));  // x_max is outside
}

// ------------------------------------------------------------------------------------------
// Report counts.

TEST(MapTracks, CheckSceneTracksCountsEachReason) {
  MapScene scene;
  scene.name = "hand";
  scene.raster.extent = Eigen::Vector4d(0, 10, 0, 10);
  scene.raster.resolution = 1.0;
  scene.raster.cells.setZero(10, 10);
  scene.raster.cells(5, 4) = 1;  // x in [4, 5), y in (4, 5]
  scene.tracks.seconds_per_step = 0.4;
  auto& tracks = scene.tracks.tracks;
  tracks.push_back(MakeTrack(0, Line(1, 1, 0.5, 0, 3)));    // too short
  tracks.push_back(MakeTrack(1, Line(1, 2, 1.0, 0, 6)));    // free, inside
  tracks.push_back(MakeTrack(2, Line(6, 8, 1.0, 0, 6)));    // x reaches 11: outside
  tracks.push_back(MakeTrack(3, Line(4.2, 1.5, 0, 1, 6)));  // y 4.5 on the obstacle
  std::vector<Eigen::Vector2d> nan_points = Line(1, 7, 0.5, 0, 6);
  nan_points[2].x() = std::nan("");
  tracks.push_back(MakeTrack(4, nan_points));  // not finite: outside
  std::vector<Eigen::Vector2d> both = Line(4.5, 4.5, 0, 0.1, 4);
  both.emplace_back(20, 20);
  tracks.push_back(MakeTrack(5, both));  // too short before outside: counted once
  std::vector<Eigen::Vector2d> twice = Line(1, 4.5, 0.5, 0, 10);  // x 4.0 and 4.5 on it
  tracks.push_back(MakeTrack(6, twice));

  MapTracksReport report;
  report.tracks_read = 100;  // counts are added to
  CheckSceneTracks(&scene, 6, &report);
  EXPECT_EQ(report.tracks_read, 107);
  EXPECT_EQ(report.tracks_kept, 3);
  EXPECT_EQ(report.too_short, 2);
  EXPECT_EQ(report.outside_frame, 2);
  EXPECT_EQ(report.points_in_obstacles, 1 + 2);
  EXPECT_EQ(report.tracks_in_obstacles, 2);
  EXPECT_EQ(report.points_kept, 6 + 6 + 10);  // tracks 1, 3, 6
  EXPECT_EQ(report.scenes, 0);
  ASSERT_EQ(scene.tracks.tracks.size(), 3u);
  EXPECT_EQ(scene.tracks.tracks[0].agent_id, 1);
  EXPECT_EQ(scene.tracks.tracks[1].agent_id, 3);
  EXPECT_EQ(scene.tracks.tracks[2].agent_id, 6);
  EXPECT_NE(report.BriefReport().find("3/107 tracks kept"), std::string::npos)
      << report.BriefReport();

  // Brute force over the kept tracks: the obstacle count is the number of samples in the box.
  int in_box = 0;
  for (const Track& t : scene.tracks.tracks)
    for (Eigen::Index i = 0; i < t.positions.rows(); ++i)
      in_box += t.positions(i, 0) >= 4 && t.positions(i, 0) < 5 && t.positions(i, 1) > 4 &&
                t.positions(i, 1) <= 5;
  EXPECT_EQ(in_box, report.points_in_obstacles);
}

/// A 40 x 40 Occ-Traj120 map: border wall, free inside, one occupied cell at row 20, column 10.
std::string SmallOccTrajMap() {
  std::ostringstream os;
  for (int r = 0; r < 40; ++r) {
    os << (r == 0 ? "[[" : " [");
    for (int c = 0; c < 40; ++c) {
      const bool occ = r == 0 || r == 39 || c == 0 || c == 39 || (r == 20 && c == 10);
      os << (occ ? 1 : 0) << (c + 1 < 40 ? " " : "");
    }
    os << (r == 39 ? "]]\n" : "]\n");
  }
  return os.str();
}

TEST(MapTracks, OccTrajFilesLoadWithReportCounts) {
  TempDir dir;
  const std::string root = dir.path() + "/occ_traj120";
  std::filesystem::create_directories(root + "/maps");
  std::filesystem::create_directories(root + "/trajs");
  WriteText(root + "/train_maps.txt", "abc\n");
  WriteText(root + "/maps/occtraj_abc_map.txt", SmallOccTrajMap());
  WriteText(
      root + "/trajs/occtraj_abc_trajs.txt",
      "traj-0:\n 2.5 3.5 4.5 5.5 6.5 7.5\n 5.0 5.0 5.0 5.0 5.0 5.0\n"            // free, kept
      "traj-1:\n 2.5 3.5 4.5\n 6.0 6.0 6.0\n"                                    // too short
      "traj-2:\n 8.5 9.5 10.5 11.5 12.5 13.5\n 20.5 20.5 20.5 20.5 20.5 20.5\n"  // 1 on (20,10)
      "traj-3:\n 35.5 37.5 39.5 41.5 43.5 45.5\n 5.0 5.0 5.0 5.0 5.0 5.0\n"      // leaves the grid
      "traj-4:\n 3.0\n 3.0\n"                                                    // 1 waypoint
      "traj-5:\n 9.5 10.0 10.5 11.0 11.5 12.0\n 21.0 21.0 21.0 21.0 21.0 21.0\n");  // y=21: free
  MapTracksConfig config;
  config.source = "occ_traj";
  config.root = dir.path();
  for (double resolution : {1.0, 0.1}) {
    config.resolution = resolution;
    MapTracksReport report;
    const std::vector<MapScene> scenes = LoadMapScenes(config, 5, &report);
    ASSERT_EQ(scenes.size(), 1u);
    const MapScene& s = scenes[0];
    EXPECT_EQ(s.name, "occtraj_abc");
    EXPECT_DOUBLE_EQ(s.tracks.seconds_per_step, 1.0);
    EXPECT_DOUBLE_EQ(s.raster.resolution, resolution);
    ASSERT_EQ(s.tracks.tracks.size(), 3u);
    EXPECT_EQ(s.tracks.tracks[1].time[5], 5.0);
    EXPECT_EQ(report.scenes, 1);
    EXPECT_EQ(report.tracks_read, 6);
    EXPECT_EQ(report.tracks_kept, 3);
    EXPECT_EQ(report.too_short, 2);
    EXPECT_EQ(report.outside_frame, 1);
    EXPECT_EQ(report.points_in_obstacles, 1);  // (10.5, 20.5); y = 21.0 is row 21, free
    EXPECT_EQ(report.tracks_in_obstacles, 1);
    EXPECT_TRUE(s.raster.Occupied(10.5, 20.5));
    EXPECT_FALSE(s.raster.Occupied(10.5, 21.0));
    EXPECT_TRUE(s.raster.Occupied(10.5, 20.0));
  }
  config.scenes = {"abd"};
  ExpectErrorContains([&] { LoadMapScenes(config, 5, nullptr); },
                      {"data.scenes", "abd", "occtraj_abd_map.txt", "not found", "data.root"});
}

TEST(MapTracks, MissingFilesAndBadConfigsNameTheKey) {
  TempDir dir;
  MapTracksConfig thor;
  thor.source = "thor";
  thor.root = dir.path();
  ExpectErrorContains([&] { LoadMapScenes(thor, 22, nullptr); },
                      {"data.scenes", "thor1", "thor1_exp-1-run-2.csv", "not found", "data.root"});
  MapTracksConfig eth;
  eth.source = "eth";
  eth.root = dir.path();
  eth.scenes = {"seq_hotel"};
  ExpectErrorContains([&] { LoadMapScenes(eth, 22, nullptr); },
                      {"data.scenes", "seq_hotel", "obsmat.txt", "not found"});

  const auto bad = [](auto edit, std::vector<std::string> parts) {
    MapTracksConfig c;
    edit(&c);
    ExpectErrorContains([&] { c.Validate("c.yaml"); }, parts);
  };
  bad([](MapTracksConfig* c) { c->source = "traffic"; }, {"c.yaml", "data.source", "'traffic'"});
  bad(
      [](MapTracksConfig* c) {
        c->source = "thor";
        c->scenes = {"thor2"};
      },
      {"c.yaml", "data.scenes", "'thor2'", "thor1, thor3"});
  bad(
      [](MapTracksConfig* c) {
        c->source = "eth";
        c->scenes = {"seq_eth", "seq_eth"};
      },
      {"data.scenes", "'seq_eth'", "twice"});
  bad([](MapTracksConfig* c) { c->scenes = {"x"}; }, {"data.scenes", "synthetic"});
  bad(
      [](MapTracksConfig* c) {
        c->source = "occ_traj";
        c->resolution = 0.3;
      },
      {"data.resolution", "0.3"});
  bad(
      [](MapTracksConfig* c) {
        c->source = "thor";
        c->max_gap = 0.2;
      },
      {"data.max_gap", "data.step"});
  MapTracksConfig ok;
  ok.source = "occ_traj";
  ok.resolution = 0.25;
  ok.Validate("c.yaml");
}

TEST(MapTracks, ConfigReadsStrictlyAndRoundTrips) {
  const MapTracksConfig c = config::ExperimentConfigFromYaml<MapTracksConfig>(
      "source: eth\nscenes: [seq_hotel]\nresolution: 0.2\nstep: 0.4\nmax_gap: 2\n"
      "synthetic_seed: 9\n",
      "data.yaml");
  EXPECT_EQ(c.source, "eth");
  EXPECT_EQ(c.scenes, std::vector<std::string>{"seq_hotel"});
  EXPECT_DOUBLE_EQ(c.resolution, 0.2);
  EXPECT_DOUBLE_EQ(c.max_gap, 2.0);
  EXPECT_EQ(c.synthetic_seed, 9);
  const MapTracksConfig back =
      config::ExperimentConfigFromYaml<MapTracksConfig>(config::ToYaml(c), "resolved.yaml");
  EXPECT_EQ(back.scenes, c.scenes);
  EXPECT_DOUBLE_EQ(back.resolution, c.resolution);
  ExpectErrorContains(
      [] { config::ExperimentConfigFromYaml<MapTracksConfig>("max_maps: 0\n", "data.yaml"); },
      {"data.yaml", "max_maps"});
  ExpectErrorContains(
      [] { config::ExperimentConfigFromYaml<MapTracksConfig>("scene: [a]\n", "data.yaml"); },
      {"data.yaml", "scene"});
}

// ------------------------------------------------------------------------------------------
// Splits.

std::set<std::pair<std::string, std::int64_t>> Keys(const std::vector<MapScene>& scenes) {
  std::set<std::pair<std::string, std::int64_t>> keys;
  for (const MapScene& s : scenes)
    for (const Track& t : s.tracks.tracks) keys.insert({s.name, t.agent_id});
  return keys;
}

TEST(MapTracks, SplitByScenePartitionsWholeScenesDeterministically) {
  const std::vector<MapScene> scenes = GenerateMapScenes(10, 3, 12, 5);
  const MapTracksSplit a = SplitMapScenes(scenes, true, 0.2, 0.2, 11);
  const MapTracksSplit b = SplitMapScenes(scenes, true, 0.2, 0.2, 11);
  const auto names = [](const std::vector<MapScene>& v) {
    std::vector<std::string> n;
    for (const MapScene& s : v) n.push_back(s.name);
    return n;
  };
  EXPECT_EQ(names(a.train), names(b.train));
  EXPECT_EQ(names(a.val), names(b.val));
  EXPECT_EQ(names(a.test), names(b.test));
  EXPECT_EQ(a.train.size(), 6u);
  EXPECT_EQ(a.val.size(), 2u);
  EXPECT_EQ(a.test.size(), 2u);
  std::set<std::string> all;
  for (const auto* part : {&a.train, &a.val, &a.test})
    for (const MapScene& s : *part) EXPECT_TRUE(all.insert(s.name).second) << s.name;
  EXPECT_EQ(all.size(), 10u);
  // Whole scenes: the same tracks and raster as the input scene.
  for (const MapScene& s : a.test) {
    const int k = std::stoi(s.name.substr(std::string("synthetic_").size()));
    EXPECT_EQ(s.tracks.tracks.size(), scenes[k].tracks.tracks.size());
    EXPECT_EQ(s.raster.cells, scenes[k].raster.cells);
  }
  bool differs = false;
  for (std::uint64_t seed = 12; seed < 20 && !differs; ++seed)
    differs = names(SplitMapScenes(scenes, true, 0.2, 0.2, seed).test) != names(a.test);
  EXPECT_TRUE(differs);
  ExpectErrorContains(
      [&] {
        SplitMapScenes({scenes[0], scenes[1]}, true, 0.2, 0.2, 1);
      },
      {"2 maps", "non-empty"});
}

TEST(MapTracks, SplitByTrackPartitionsTracksWithinEachScene) {
  const std::vector<MapScene> scenes = GenerateMapScenes(2, 30, 12, 6);
  const MapTracksSplit a = SplitMapScenes(scenes, false, 0.2, 0.3, 3);
  const MapTracksSplit b = SplitMapScenes(scenes, false, 0.2, 0.3, 3);
  EXPECT_EQ(Keys(a.train), Keys(b.train));
  EXPECT_EQ(Keys(a.val), Keys(b.val));
  EXPECT_EQ(Keys(a.test), Keys(b.test));
  std::set<std::pair<std::string, std::int64_t>> all;
  std::size_t total = 0;
  for (const auto* part : {&a.train, &a.val, &a.test}) {
    const auto k = Keys(*part);
    total += k.size();
    all.insert(k.begin(), k.end());
  }
  EXPECT_EQ(total, all.size());  // disjoint
  EXPECT_EQ(all, Keys(scenes));  // complete
  ASSERT_EQ(a.test.size(), 2u);  // both scenes in every part, each with its own raster
  for (const MapScene& s : a.test) {
    EXPECT_EQ(s.tracks.tracks.size(), 9u);  // round(0.3 * 30)
    const MapScene& src = s.name == scenes[0].name ? scenes[0] : scenes[1];
    EXPECT_EQ(s.raster.cells, src.raster.cells);
  }
  EXPECT_NE(Keys(SplitMapScenes(scenes, false, 0.2, 0.3, 4).test), Keys(a.test));
}

// ------------------------------------------------------------------------------------------
// Synthetic generator.

TEST(MapTracks, GeneratorIsDeterministicAndEverySampleIsFree) {
  const int min_points = 22;
  const std::vector<MapScene> a = GenerateMapScenes(20, 40, min_points, 7);
  const std::vector<MapScene> b = GenerateMapScenes(20, 40, min_points, 7);
  ASSERT_EQ(a.size(), 20u);
  int tracks = 0, points = 0, on_obstacles = 0, outside = 0;
  double path = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].name, "synthetic_" + std::to_string(k));
    EXPECT_DOUBLE_EQ(a[k].tracks.seconds_per_step, 0.4);
    ASSERT_EQ(a[k].tracks.tracks.size(), b[k].tracks.tracks.size());
    EXPECT_EQ(a[k].raster.cells, b[k].raster.cells);
    EXPECT_GE(a[k].tracks.tracks.size(), 36u);  // nearly all requested tracks
    EXPECT_GT((a[k].raster.cells.array() != 0).count(), 0);
    for (std::size_t j = 0; j < a[k].tracks.tracks.size(); ++j) {
      const Track& t = a[k].tracks.tracks[j];
      EXPECT_EQ(t.positions, b[k].tracks.tracks[j].positions);
      EXPECT_GE(t.size(), min_points);
      ++tracks;
      for (Eigen::Index i = 0; i < t.positions.rows(); ++i) {
        ++points;
        on_obstacles += a[k].raster.Occupied(t.positions(i, 0), t.positions(i, 1));
        outside += !InsideRaster(a[k].raster, t.positions(i, 0), t.positions(i, 1));
        if (i > 0) path += (t.positions.row(i) - t.positions.row(i - 1)).norm();
      }
    }
  }
  EXPECT_EQ(on_obstacles, 0);
  EXPECT_EQ(outside, 0);
  const double speed = path / ((points - tracks) * 0.4);
  EXPECT_GT(speed, 1.0);
  EXPECT_LT(speed, 1.45);
  EXPECT_NE(GenerateMapScenes(1, 5, min_points, 8)[0].tracks.tracks[0].positions,
            a[0].tracks.tracks[0].positions);
}

TEST(MapTracks, SomeSyntheticTracksCurveWhereConstantVelocityHitsAnObstacle) {
  const std::vector<MapScene> scenes = GenerateMapScenes(5, 40, 22, 3);
  int windows = 0, cv_hits = 0;
  for (const MapScene& s : scenes)
    for (const Track& t : s.tracks.tracks)
      for (int start = 0; start + 22 <= t.size(); start += 4) {
        ++windows;
        const Eigen::Vector2d last = t.positions.row(start + 9).transpose();
        const Eigen::Vector2d v = last - t.positions.row(start + 8).transpose();
        // The first occupied point of the extrapolation, if it is not the border wall.
        const Eigen::Vector4d& e = s.raster.extent;
        for (int k = 1; k <= 12; ++k) {
          const Eigen::Vector2d p = last + k * v;
          if (!s.raster.Occupied(p.x(), p.y())) continue;
          cv_hits +=
              p.x() > e[0] + 0.5 && p.x() < e[1] - 0.5 && p.y() > e[2] + 0.5 && p.y() < e[3] - 0.5;
          break;
        }
      }
  ASSERT_GT(windows, 0);
  // The ground truth stays free (previous test); a constant velocity runs into the block or a
  // pillar in a clear share of windows.
  EXPECT_GT(cv_hits, windows / 20) << cv_hits << " of " << windows;
  std::cout << "constant velocity hits an interior obstacle in " << cv_hits << " of " << windows
            << " windows\n";
}

TEST(MapTracks, SyntheticSourceLoadsThroughTheConfig) {
  MapTracksConfig config;
  config.max_maps = 3;
  config.synthetic_tracks = 10;
  config.synthetic_seed = 4;
  MapTracksReport report;
  const std::vector<MapScene> scenes = LoadMapScenes(config, 22, &report);
  ASSERT_EQ(scenes.size(), 3u);
  int kept = 0;
  for (const MapScene& s : scenes) kept += static_cast<int>(s.tracks.tracks.size());
  EXPECT_EQ(report.scenes, 3);
  EXPECT_EQ(report.tracks_kept, kept);
  EXPECT_EQ(report.tracks_read, kept);
  EXPECT_EQ(report.points_in_obstacles, 0);
  const std::vector<MapScene> direct = GenerateMapScenes(3, 10, 22, 4);
  EXPECT_EQ(direct[2].tracks.tracks.back().positions, scenes[2].tracks.tracks.back().positions);
}

// ------------------------------------------------------------------------------------------
// Real data (skipped when ../shared/data is absent).

std::string DataRoot(const std::string& probe) {
  const std::string data = foresight::testing::SharedDataDir();
  if (data.empty() || !std::filesystem::exists(data + "/" + probe)) return "";
  return data;
}

void ExpectMostlyFree(const std::vector<MapScene>& scenes, const MapTracksReport& report,
                      double min_free_share) {
  int points = 0, occupied = 0, outside = 0;
  for (const MapScene& s : scenes)
    for (const Track& t : s.tracks.tracks)
      for (Eigen::Index i = 0; i < t.positions.rows(); ++i) {
        ++points;
        occupied += s.raster.Occupied(t.positions(i, 0), t.positions(i, 1));
        outside += !InsideRaster(s.raster, t.positions(i, 0), t.positions(i, 1));
      }
  ASSERT_GT(points, 0);
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(occupied, report.points_in_obstacles);
  EXPECT_EQ(points, report.points_kept);
  EXPECT_GE(1.0 - static_cast<double>(occupied) / points, min_free_share) << report.BriefReport();
}

TEST(MapTracks, RealThorLoadsMostlyOnFreeCells) {
  const std::string root = DataRoot("thor/thor1_exp-1-run-2.csv");
  if (root.empty()) GTEST_SKIP() << "../shared/data/thor is absent: skipping the THOR scenes";
  MapTracksConfig config;
  config.source = "thor";
  config.root = root;
  MapTracksReport report;
  const std::vector<MapScene> scenes = LoadMapScenes(config, 22, &report);
  ASSERT_EQ(scenes.size(), 2u);
  EXPECT_EQ(scenes[0].name, "thor1");
  EXPECT_EQ(scenes[1].name, "thor3");
  EXPECT_DOUBLE_EQ(scenes[0].tracks.seconds_per_step, 0.4);
  EXPECT_GT(report.tracks_kept, 40);
  EXPECT_GT(report.too_short, 0);  // tracklets of 1 .. 115 samples
  EXPECT_EQ(report.tracks_read, report.tracks_kept + report.too_short + report.outside_frame);
  for (const MapScene& s : scenes) {  // the README's room, clipped
    EXPECT_GE(s.raster.extent[0], -11.0);
    EXPECT_LE(s.raster.extent[3], 13.5);
  }
  ExpectMostlyFree(scenes, report, 0.95);
  std::cout << "THOR: " << report.BriefReport() << "\n";
}

TEST(MapTracks, RealEthLoadsMostlyOnFreeCells) {
  const std::string root = DataRoot("eth_ucy/eth_original/seq_hotel/obsmat.txt");
  if (root.empty()) GTEST_SKIP() << "../shared/data/eth_ucy/eth_original is absent: skipping ETH";
  MapTracksConfig config;
  config.source = "eth";
  config.root = root;
  MapTracksReport report;
  const std::vector<MapScene> scenes = LoadMapScenes(config, 22, &report);
  ASSERT_EQ(scenes.size(), 2u);
  EXPECT_EQ(scenes[0].name, "seq_eth");
  EXPECT_EQ(scenes[1].name, "seq_hotel");
  EXPECT_GT(report.tracks_kept, 100);
  EXPECT_EQ(report.tracks_read, report.tracks_kept + report.too_short + report.outside_frame);
  ExpectMostlyFree(scenes, report, 0.95);
  std::cout << "ETH: " << report.BriefReport() << "\n";
}

TEST(MapTracks, RealOccTrajWaypointsAreAllFree) {
  const std::string root = DataRoot("occ_traj120/train_maps.txt");
  if (root.empty()) GTEST_SKIP() << "../shared/data/occ_traj120 is absent: skipping Occ-Traj120";
  MapTracksConfig config;
  config.source = "occ_traj";
  config.root = root;
  config.max_maps = 3;
  config.resolution = 1.0;
  MapTracksReport report;
  const std::vector<MapScene> scenes = LoadMapScenes(config, 20, &report);
  ASSERT_EQ(scenes.size(), 3u);
  EXPECT_EQ(scenes[0].name, "occtraj_0209bae1c9");
  EXPECT_EQ(report.tracks_read, 600);
  EXPECT_EQ(report.outside_frame, 0);
  EXPECT_GT(report.too_short, 0);  // 5 .. 58 waypoints
  EXPECT_EQ(report.points_in_obstacles, 0);
  ExpectMostlyFree(scenes, report, 1.0);
}

}  // namespace
}  // namespace foresight
