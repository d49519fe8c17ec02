#include "datasets/crowd_scenario.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <set>

#include "datasets/crowd_sim.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

// The snippets of docs/dataset_schema.md ("Crowd scenarios"): they must stay equal to the
// factories.
constexpr const char* kSim1Yaml = R"(
name: sim1
source: simulated
extent: [-10, 10, -4, 4]          # 20 m x 8 m hall
walls:                            # a partition at x = 0 with a 2 m doorway
  - {x0: 0, y0: -4, x1: 0, y1: -1}
  - {x0: 0, y0: 1, x1: 0, y1: 4}
wall_thickness: 0.2
groups:                           # two opposing flows through the doorway, back and forth
  - {count: 12, spawn: [-7.5, -1.5, -3.5, 3.5], goal: [1.5, 7.5, -3.5, 3.5],
     preferred_speed: 0.9, speed_jitter: 0.1, round_trip: true}
  - {count: 12, spawn: [1.5, 7.5, -3.5, 3.5], goal: [-7.5, -1.5, -3.5, 3.5],
     preferred_speed: 0.9, speed_jitter: 0.1, round_trip: true}
pedestrian_radius: 0.4
power_law: {k: 1.5, exponent: 2, tau0: 1.5, relaxation: 0.3, max_accel: 20, max_speed: 1.0}
robot_start: [-9, 0, 0]
robot_goal: [9, 0]
start_jitter: 0.3
)";

constexpr const char* kSim2Yaml = R"(
name: sim2
source: simulated
extent: [-10, 10, -10, 10]        # open 20 m x 20 m area, no walls
groups:                           # four loosely crossing flows of 6
  - {count: 6, spawn: [-9.5, -6.5, -5, 5], goal: [6.5, 9.5, -5, 5], preferred_speed: 0.9}
  - {count: 6, spawn: [6.5, 9.5, -5, 5], goal: [-9.5, -6.5, -5, 5], preferred_speed: 0.9}
  - {count: 6, spawn: [-5, 5, -9.5, -6.5], goal: [-5, 5, 6.5, 9.5], preferred_speed: 0.9}
  - {count: 6, spawn: [-5, 5, 6.5, 9.5], goal: [-5, 5, -9.5, -6.5], preferred_speed: 0.9}
robot_start: [-8.5, -8.5, 0.7853981633974483]
robot_goal: [8.5, 8.5]
start_jitter: 0.3
)";

CrowdScenarioConfig FromText(const std::string& text) {
  return config::FromYaml<CrowdScenarioConfig>(config::ParseYaml(text, "scene.yaml"), "scene.yaml");
}

TEST(CrowdScenario, DocumentedSnippetsEqualTheFactories) {
  EXPECT_EQ(config::ToYaml(FromText(kSim1Yaml)), config::ToYaml(Sim1Scenario()));
  EXPECT_EQ(config::ToYaml(FromText(kSim2Yaml)), config::ToYaml(Sim2Scenario()));
  for (const CrowdScenarioConfig& s : {Sim1Scenario(), Sim2Scenario()}) {
    s.Validate(s.name);
    int pedestrians = 0;
    for (const auto& g : s.groups) pedestrians += g.count;
    EXPECT_EQ(pedestrians, 24) << s.name;
    const std::string text = config::ToYaml(s);
    EXPECT_EQ(config::ToYaml(FromText(text)), text) << s.name;  // round trip
  }
  const std::string table = config::ReferenceTable<CrowdScenarioConfig>();
  for (const char* key : {"`walls[].x0`", "`groups[].spawn`", "`groups[].round_trip`",
                          "`power_law.tau0`", "`replay.overlay_spacing`"})
    EXPECT_NE(table.find(key), std::string::npos) << key;
}

TEST(CrowdScenario, ConfigErrorsNameTheKey) {
  testing::ExpectErrorContains([] { FromText("groups:\n  - {count: 0}\n"); },
                               {"scene.yaml:2", "'groups[0].count'", ">= 1"});
  testing::ExpectErrorContains([] { FromText("groups:\n  - {cout: 3}\n"); },
                               {"unknown key 'groups[0].cout'"});
  testing::ExpectErrorContains([] { FromText("source: recorded\n"); },
                               {"'source'", "'simulated'", "'replay'"});
  testing::ExpectErrorContains([] { FromText("power_law: {max_speed: -1}\n"); },
                               {"'power_law.max_speed'"});
}

TEST(CrowdScenario, ValidateRejectsInconsistentScenes) {
  const auto expect = [](const std::function<void(CrowdScenarioConfig*)>& edit,
                         const std::vector<std::string>& parts) {
    CrowdScenarioConfig s = Sim1Scenario();
    edit(&s);
    testing::ExpectErrorContains([&] { s.Validate("scene.yaml"); }, parts);
  };
  expect(
      [](CrowdScenarioConfig* s) {
        s->extent = {1, 1, 0, 4};
      },
      {"scene.yaml", "'extent'", "empty"});
  expect([](CrowdScenarioConfig* s) { s->extent = {0, 1}; }, {"'extent'", "4 finite"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->robot_goal = {12, 0};
      },
      {"'robot_goal'", "(12, 0)", "not inside"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->robot_start = {-9, 0};
      },
      {"'robot_start'", "[x, y, heading]"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->robot_start = {0.2, 2, 0};
      },
      {"'robot_start'", "collision", "walls[1]"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->robot_goal = {0, -3};
      },
      {"'robot_goal'", "collision", "walls[0]"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->walls.push_back({0, 0, 15, 0});
      },
      {"'walls[2]'", "outside the extent"});
  expect([](CrowdScenarioConfig* s) { s->groups.clear(); },
         {"no pedestrian groups", "empty crowd"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->groups[1].spawn = {2, 1, 0, 1};
      },
      {"'groups[1].spawn'", "malformed"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->groups[0].goal = {0, 1, 0};
      },
      {"'groups[0].goal'", "4 finite"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->groups[0].goal = {0, 11, 0, 1};
      },
      {"'groups[0].goal'", "not inside"});
  expect([](CrowdScenarioConfig* s) { s->groups[0].count = 0; }, {"'groups[0].count'"});
  // Faster than the simulator's cap (1 m/s): 0.95 + 0.1 jitter.
  expect([](CrowdScenarioConfig* s) { s->groups[1].preferred_speed = 0.95; },
         {"'groups[1].preferred_speed' = 0.95", "speed_jitter 0.1", "power_law.max_speed = 1"});
  expect(
      [](CrowdScenarioConfig* s) {
        s->source = CrowdSource::kReplay;
        s->replay.format = "csv";
      },
      {"'replay.format'", "'csv'", "thor or eth_obsmat"});
  CrowdScenarioConfig s = Sim1Scenario();
  s.robot_goal = {std::nan(""), 0};
  testing::ExpectErrorContains([&] { MakeCrowd(s, 1); }, {"'robot_goal'"});
}

TEST(CrowdScenario, Sim1OccupancyHasTheWallsTheDoorwayAndTheOutside) {
  const CrowdScenarioConfig s = Sim1Scenario();
  const OccupancyRaster r = ScenarioOccupancy(s, 0.05);
  EXPECT_EQ(r.cells.rows(), 160);
  EXPECT_EQ(r.cells.cols(), 400);
  EXPECT_TRUE(r.Occupied(0.0, 2.5));
  EXPECT_TRUE(r.Occupied(0.08, -2.5));
  EXPECT_FALSE(r.Occupied(0.0, 0.0));  // the doorway
  EXPECT_FALSE(r.Occupied(0.2, 2.5));  // beside the wall
  EXPECT_TRUE(r.Occupied(0.0, 4.1));   // outside the extent
  EXPECT_TRUE(r.Occupied(-10.1, 0.0));
  EXPECT_FALSE(r.Occupied(s.robot_start[0], s.robot_start[1]));
  EXPECT_FALSE(r.Occupied(s.robot_goal[0], s.robot_goal[1]));
  // Row 0 is y_max, column 0 is x_min.
  EXPECT_EQ(r.cells(0, 200), 1);
  EXPECT_EQ(r.cells(80, 200), 0);
  const OccupancyRaster open = ScenarioOccupancy(Sim2Scenario(), 0.1);
  EXPECT_EQ(open.cells.sum(), 0);
}

TEST(CrowdScenario, EpisodeEndpointsAreJitteredDeterministically) {
  const CrowdScenarioConfig s = Sim1Scenario();
  const EpisodeEndpoints a = MakeEpisodeEndpoints(s, 3), b = MakeEpisodeEndpoints(s, 3),
                         c = MakeEpisodeEndpoints(s, 4);
  EXPECT_EQ(a.start, b.start);
  EXPECT_EQ(a.goal, b.goal);
  EXPECT_NE(a.start, c.start);
  EXPECT_LE((a.start.head<2>() - Eigen::Vector2d(-9, 0)).cwiseAbs().maxCoeff(), 0.3);
  EXPECT_LE((a.goal - Eigen::Vector2d(9, 0)).cwiseAbs().maxCoeff(), 0.3);
  EXPECT_EQ(a.start.z(), 0.0);
}

TEST(CrowdScenario, Sim1CongestsAtTheDoorwayAndNoOneWalksThroughWalls) {
  const CrowdScenarioConfig s = Sim1Scenario();
  const std::unique_ptr<Crowd> crowd = MakeCrowd(s, 7);
  RobotAgent robot;  // standing at the start
  robot.position = {-9, 0};
  const auto n = crowd->agents().size();
  std::vector<Eigen::Vector2d> last(n);
  for (std::size_t i = 0; i < n; ++i) last[i] = crowd->agents()[i].position;
  int crossings = 0, through_walls = 0;
  double speed_sum = 0, min_gap = 1e9;
  int speed_count = 0;
  for (int k = 0; k < 400; ++k) {
    crowd->Step(0.1, robot);
    const auto& a = crowd->agents();
    for (std::size_t i = 0; i < n; ++i) {
      if ((last[i].x() < 0) != (a[i].position.x() < 0)) {
        ++crossings;
        const double y = 0.5 * (last[i].y() + a[i].position.y());
        through_walls += std::abs(y) > 1.0;
      }
      last[i] = a[i].position;
      if (crowd->time() > 10) {
        speed_sum += a[i].velocity.norm();
        ++speed_count;
      }
      for (std::size_t j = i + 1; j < n; ++j)
        min_gap =
            std::min(min_gap, (a[i].position - a[j].position).norm() - a[i].radius - a[j].radius);
    }
  }
  const double mean_speed = speed_sum / speed_count;
  EXPECT_EQ(through_walls, 0);
  EXPECT_GT(crossings, 10);     // the flows do get through the doorway
  EXPECT_LT(mean_speed, 0.75);  // against ~0.9 m/s preferred: congestion
  EXPECT_GT(min_gap, -0.4);     // pushing, but no pedestrian walks through another
  std::cout << "[ sim1, 40 s ] doorway crossings " << crossings << ", mean speed after 10 s "
            << mean_speed << " m/s (preferred 0.8-1.0), min gap " << min_gap << " m\n";
}

TEST(CrowdScenario, RecordedTracksCoverEveryPedestrianOfEveryEpisode) {
  const CrowdScenarioConfig s = Sim2Scenario();
  const TrackSet a = RecordCrowdTracks(s, 2, 8.0, 0.4, 5);
  const TrackSet b = RecordCrowdTracks(s, 2, 8.0, 0.4, 5);
  ASSERT_EQ(a.tracks.size(), 48u);
  EXPECT_DOUBLE_EQ(a.seconds_per_step, 0.4);
  EXPECT_EQ(a.source, "crowd:sim2");
  std::set<std::int64_t> ids;
  for (std::size_t t = 0; t < a.tracks.size(); ++t) {
    const Track& tr = a.tracks[t];
    ids.insert(tr.agent_id);
    ASSERT_EQ(tr.size(), 21);
    EXPECT_NEAR(tr.time.back(), 8.0, 1e-9);
    EXPECT_TRUE(tr.positions.allFinite());
    EXPECT_TRUE(tr.positions.isApprox(b.tracks[t].positions));
    for (int k = 1; k < tr.size(); ++k)
      EXPECT_LE((tr.positions.row(k) - tr.positions.row(k - 1)).norm(),
                0.4 * s.power_law.max_speed + 1e-9);
  }
  EXPECT_EQ(ids.size(), a.tracks.size());
  // Episodes differ.
  EXPECT_GT((a.tracks[0].positions.row(0) - a.tracks[24].positions.row(0)).norm(), 1e-6);
}

}  // namespace
}  // namespace foresight
