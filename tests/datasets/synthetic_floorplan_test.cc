#include "datasets/synthetic_floorplan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "datasets/occupancy_points.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

TEST(FloorPlan, RaycastMatchesAnalyticDistances) {
  FloorPlan plan;
  plan.width = 10;
  plan.height = 10;
  plan.walls = {Eigen::Vector4d(5, -1, 5, 1),   // vertical wall at x = 5, y in [-1, 1]
                Eigen::Vector4d(0, 3, 10, 3)};  // horizontal wall at y = 3
  const Eigen::Vector2d o(1, 0);
  EXPECT_NEAR(plan.Raycast(o, 0.0, 20), 4.0, 1e-12);
  EXPECT_NEAR(plan.Raycast(o, M_PI / 2, 20), 3.0, 1e-12);
  // 30 degrees up: the ray passes x = 5 at y = 4 tan 30 = 2.31, above the vertical wall, and
  // reaches y = 3 at distance 3 / sin 30 = 6.
  EXPECT_NEAR(plan.Raycast(o, M_PI / 6, 20), 6.0, 1e-12);
  // 10 degrees up: hits x = 5 at y = 4 tan 10 = 0.705 < 1, distance 4 / cos 10.
  EXPECT_NEAR(plan.Raycast(o, 10 * M_PI / 180, 20), 4.0 / std::cos(10 * M_PI / 180), 1e-12);
  EXPECT_TRUE(std::isinf(plan.Raycast(o, M_PI, 20)));  // nothing behind
  EXPECT_TRUE(std::isinf(plan.Raycast(o, -M_PI / 2, 20)));
  EXPECT_TRUE(std::isinf(plan.Raycast(o, 0.0, 3.9)));  // beyond max_range
  EXPECT_NEAR(plan.Raycast(o, 0.0, 4.0), 4.0, 1e-12);
  EXPECT_TRUE(plan.Occupied({5.05, 0.5}, 0.06));
  EXPECT_FALSE(plan.Occupied({5.1, 0.5}, 0.06));
  EXPECT_TRUE(plan.Occupied({5.0, 1.04}, 0.05));  // near the end point
  EXPECT_FALSE(plan.Occupied({5.0, 1.2}, 0.05));
}

TEST(FloorPlan, RoomsAreConnectedByDoorsOnAWallGrid) {
  const SyntheticFloorplanConfig cfg;
  const FloorPlan plan = GenerateFloorPlan(cfg, 5);
  ASSERT_EQ(plan.room_centres.size(), 6u);
  ASSERT_EQ(plan.doors.size(), 5u);  // a spanning tree of 6 rooms
  std::vector<int> parent{0, 1, 2, 3, 4, 5};
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i];
    return i;
  };
  for (const auto& d : plan.doors) {
    parent[find(d.room_a)] = find(d.room_b);
    // A door is an opening: its centre is free, and walls are at the door edges' side.
    EXPECT_FALSE(plan.Occupied(d.centre, 0.45));
    const Eigen::Vector2d along(-d.normal.y(), d.normal.x());
    EXPECT_TRUE(plan.Occupied(d.centre + 0.5 * cfg.door_width * along + 0.05 * along, 0.06));
    // Rays through the door along its normal pass into the neighbouring room.
    EXPECT_GT(plan.Raycast(d.centre - 0.5 * d.normal, std::atan2(d.normal.y(), d.normal.x()), 30),
              1.0);
  }
  for (int r = 0; r < 6; ++r) EXPECT_EQ(find(r), find(0)) << "room " << r << " is unreachable";
  // Outer walls: a ray from any room centre hits something within the plan.
  for (const auto& c : plan.room_centres)
    for (double a = 0; a < 2 * M_PI; a += 0.1) EXPECT_LT(plan.Raycast(c, a, 100), 26.0);
  // Deterministic in the seed; another seed moves doors.
  const FloorPlan again = GenerateFloorPlan(cfg, 5), other = GenerateFloorPlan(cfg, 6);
  ASSERT_EQ(again.walls.size(), plan.walls.size());
  for (std::size_t i = 0; i < plan.walls.size(); ++i) EXPECT_EQ(again.walls[i], plan.walls[i]);
  bool differs = other.walls.size() != plan.walls.size();
  for (std::size_t i = 0; !differs && i < plan.walls.size(); ++i)
    differs = other.walls[i] != plan.walls[i];
  EXPECT_TRUE(differs);
}

TEST(FloorPlan, BadGeometryIsAnError) {
  SyntheticFloorplanConfig cfg;
  cfg.rooms_x = 1;
  cfg.rooms_y = 1;
  testing::ExpectErrorContains([&] { GenerateFloorPlan(cfg, 1); }, {"at least 2 rooms"});
  cfg = {};
  cfg.rooms_x = 20;
  testing::ExpectErrorContains([&] { GenerateFloorPlan(cfg, 1); }, {"too small", "door_width"});
  cfg = {};
  testing::ExpectErrorContains([&] { SimulateRobots(FloorPlan{}, cfg, 1); }, {"at least 2 rooms"});
  testing::ExpectErrorContains(
      [] {
        config::FromYaml<SyntheticFloorplanConfig>(config::ParseYaml("num_robots: 9\n", "f.yaml"),
                                                   "f.yaml");
      },
      {"f.yaml", "num_robots"});
}

class SimulatedRobots : public ::testing::Test {
 protected:
  void SetUp() override {
    plan_ = GenerateFloorPlan(cfg_, 3);
    scans_ = SimulateRobots(plan_, cfg_, 4);
  }
  SyntheticFloorplanConfig cfg_;
  FloorPlan plan_;
  std::vector<LaserScan> scans_;
};

TEST_F(SimulatedRobots, ScansHaveTheConfiguredShapeAndOrder) {
  ASSERT_EQ(scans_.size(), 300u);
  std::array<int, 2> per_robot{0, 0};
  for (std::size_t s = 0; s < scans_.size(); ++s) {
    const LaserScan& scan = scans_[s];
    ASSERT_TRUE(scan.robot == 0 || scan.robot == 1);
    ++per_robot[scan.robot];
    EXPECT_EQ(scan.ranges.size(), 180u);
    EXPECT_NEAR(scan.angle_min, -M_PI / 2, 1e-15);
    EXPECT_NEAR(scan.angle_increment, M_PI / 180, 1e-15);
    if (s > 0) {
      EXPECT_GT(scan.time, scans_[s - 1].time);
    }
    for (double r : scan.ranges) EXPECT_TRUE(r > 0 && std::isfinite(r));
  }
  EXPECT_EQ(per_robot[0], 150);
  EXPECT_EQ(per_robot[1], 150);
  // Deterministic.
  const auto again = SimulateRobots(plan_, cfg_, 4);
  for (std::size_t s = 0; s < scans_.size(); ++s) EXPECT_EQ(again[s].ranges, scans_[s].ranges);
}

TEST_F(SimulatedRobots, RobotsStayClearOfWallsAndMove) {
  for (const LaserScan& scan : scans_) {
    const Eigen::Vector2d p(scan.x, scan.y);
    EXPECT_FALSE(plan_.Occupied(p, 0.3)) << "robot " << scan.robot << " at " << p.transpose();
    EXPECT_TRUE(p.x() > 0 && p.x() < cfg_.width && p.y() > 0 && p.y() < cfg_.height);
  }
  // Consecutive scans of a robot are speed * scan_period apart (at most; less at corners).
  for (std::size_t s = 2; s < scans_.size(); ++s) {
    const double step = std::hypot(scans_[s].x - scans_[s - 2].x, scans_[s].y - scans_[s - 2].y);
    EXPECT_LE(step, cfg_.speed * cfg_.scan_period + 1e-9);
  }
  // Each robot gets well away from its start (scan s of robot k is at index 2 s + k).
  for (int k = 0; k < 2; ++k) {
    double farthest = 0;
    for (std::size_t s = k; s < scans_.size(); s += 2)
      farthest =
          std::max(farthest, std::hypot(scans_[s].x - scans_[k].x, scans_[s].y - scans_[k].y));
    EXPECT_GT(farthest, 4.0) << "robot " << k;
  }
}

TEST_F(SimulatedRobots, HitsLieOnWallsAndRobotsCoverDifferentRegions) {
  OccupancyPointsConfig pcfg;
  pcfg.max_range = cfg_.max_range;  // no return reads max_range
  const LabelledPoints pts = SampleLabelledPoints(scans_, pcfg, 1);
  ASSERT_GT(pts.NumOccupied(), 20000);
  std::array<Eigen::Vector2d, 2> mean_hit{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  std::array<std::int64_t, 2> hits{0, 0};
  for (int s = 0; s < pts.num_scans(); ++s) {
    for (std::int64_t k = pts.scan_begin[s]; k < pts.scan_begin[s + 1]; ++k) {
      if (!pts.occupied[k]) continue;
      const Eigen::Vector2d p = pts.xy.col(k);
      ASSERT_TRUE(plan_.Occupied(p, 6 * cfg_.range_noise))
          << "hit off the walls at " << p.transpose();
      mean_hit[pts.robot[s]] += p;
      ++hits[pts.robot[s]];
    }
  }
  // Robots start in opposite corners' rooms and explore their own parts of the plan.
  std::array<Eigen::Vector2d, 2> mean_pose{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  std::array<std::set<int>, 2> rooms_seen;
  const double room_w = cfg_.width / cfg_.rooms_x, room_h = cfg_.height / cfg_.rooms_y;
  for (const LaserScan& scan : scans_) {
    mean_pose[scan.robot] += Eigen::Vector2d(scan.x, scan.y) / 150.0;
    rooms_seen[scan.robot].insert(static_cast<int>(scan.y / room_h) * cfg_.rooms_x +
                                  static_cast<int>(scan.x / room_w));
  }
  EXPECT_GT((mean_pose[0] - mean_pose[1]).norm(), 6.0);
  EXPECT_GT((mean_hit[0] / hits[0] - mean_hit[1] / hits[1]).norm(), 4.0);
  EXPECT_TRUE(rooms_seen[0].count(0));
  EXPECT_TRUE(rooms_seen[1].count(5));
  EXPECT_FALSE(rooms_seen[0].count(5));
  EXPECT_FALSE(rooms_seen[1].count(0));
}

TEST(SimulatedRobotsMore, NoiseFreeRangesEqualRaycastsAndRobotsStartApart) {
  SyntheticFloorplanConfig cfg;
  cfg.range_noise = 0;
  cfg.num_robots = 4;
  cfg.scans_per_robot = 3;
  cfg.beams = 16;
  cfg.fov = 2 * M_PI;
  const FloorPlan plan = GenerateFloorPlan(cfg, 8);
  const auto scans = SimulateRobots(plan, cfg, 9);
  ASSERT_EQ(scans.size(), 12u);
  std::set<std::pair<long, long>> starts;
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(scans[k].robot, k);
    starts.insert({std::lround(scans[k].x * 100), std::lround(scans[k].y * 100)});
  }
  EXPECT_EQ(starts.size(), 4u);
  for (const LaserScan& s : scans) {
    for (int i = 0; i < s.num_beams(); ++i) {
      const double r = plan.Raycast({s.x, s.y}, s.BeamAngle(i), cfg.max_range);
      EXPECT_DOUBLE_EQ(s.ranges[i], std::isfinite(r) ? r : cfg.max_range);
    }
  }
}

}  // namespace
}  // namespace foresight
