// The navigation harness: a short episode per method end to end, summary.json keys, and the
// load-time errors of bad configs (unreachable or blocked goals, starts in collision, empty crowds,
// artifacts of the wrong kind).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/test_util.h"
#include "training/navigation/run.h"

namespace foresight {
namespace {

nav::ExperimentConfig SmallConfig(const testing::TempDir& dir) {
  nav::ExperimentConfig c;
  c.scenario = Sim2Scenario();
  for (auto& g : c.scenario.groups) g.count = 2;
  c.scenario.extent = {-6, 6, -6, 6};
  c.scenario.groups = {c.scenario.groups[0], c.scenario.groups[1]};
  c.scenario.groups[0].spawn = {-5.5, -4.5, -2, 2};
  c.scenario.groups[0].goal = {4.5, 5.5, -2, 2};
  c.scenario.groups[1].spawn = {4.5, 5.5, -2, 2};
  c.scenario.groups[1].goal = {-5.5, -4.5, -2, 2};
  c.scenario.robot_start = {-4.5, -4.5, 0.785};
  c.scenario.robot_goal = {4.5, 4.5};
  c.max_time = 25;
  c.episodes = 1;
  c.span.options.initialisations = 6;
  c.cl_rrt_star.options.max_iterations = 300;
  c.video.pixels_per_metre = 10;
  testing::RandomSpanSpec spec;
  spec.observed = 5;
  spec.predicted = 40;
  spec.seconds_per_step = 0.1;
  c.predictor.artifact = dir.File("predictor.h5");
  testing::WriteRandomSpanArtifact(c.predictor.artifact, spec);
  return c;
}

TEST(NavigationRun, EveryMethodRunsAnEpisodeAndTheSummaryHasItsKeys) {
  testing::TempDir dir;
  const nav::ExperimentConfig c = SmallConfig(dir);
  const std::vector<nav::MethodSummary> s = nav::RunNavigation(c, dir.path(), 1);
  ASSERT_EQ(s.size(), 3u) << "a methods list without orca is unchanged";
  for (const nav::MethodSummary& m : s) {
    EXPECT_EQ(m.episodes, 1);
    EXPECT_GE(m.cycle_ms_median, 0.0);
  }
  EXPECT_EQ(s[1].method, "reactive");
  EXPECT_EQ(s[1].success_rate, 1.0) << "the reactive robot crosses a nearly empty square";
  std::ifstream in(dir.File("summary.json"));
  std::stringstream text;
  text << in.rdbuf();
  for (const char* key : {"\"span\"",
                          "\"reactive\"",
                          "\"cl_rrt_star\"",
                          "success_rate",
                          "collision_free_rate",
                          "ttg_mean",
                          "doc_mean",
                          "min_clearance",
                          "cycle_ms_median",
                          "cycle_ms_p99",
                          "successes",
                          "success_and_collision_free_rate",
                          "success_and_collision_free",
                          "ttg_censored_mean",
                          "robot_caused_doc_mean",
                          "robot_caused_collision_free_rate",
                          "success_rate_ci",
                          "collision_free_rate_ci",
                          "success_and_collision_free_rate_ci",
                          "robot_caused_collision_free_rate_ci"})
    EXPECT_NE(text.str().find(key), std::string::npos) << key;
  for (const char* f : {"episodes.csv", "paths.png", "episode.avi", "map.h5"})
    EXPECT_TRUE(std::filesystem::exists(dir.File(f))) << f;
  EXPECT_GT(std::filesystem::file_size(dir.File("episode.avi")), 1000u);
  // episodes.csv: new columns are appended (readers by position keep working).
  std::ifstream csv(dir.File("episodes.csv"));
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header,
            "method,episode,seed,reached,ttg,doc,doc_static,min_clearance,path_length,cycles,solve_"
            "failures,cycle_ms_median,cycle_ms_p99,robot_caused_doc,blocked_cycles,stopped_time,"
            "fallback_cycles");
  for (const char* key : {"blocked_cycle_share", "stopped_time_share"})
    EXPECT_NE(text.str().find(key), std::string::npos) << key;
}

TEST(NavigationRun, OrcaIsTheFourthMethod) {
  testing::TempDir dir;
  nav::ExperimentConfig c = SmallConfig(dir);
  c.methods = {"orca", "reactive"};
  c.video.method = "orca";
  c.video.enabled = false;
  c.map.kind = nav::MapKind::kGrid;  // the map is not what this test is about
  EXPECT_EQ(nav::ParseMethod("orca", "test"), nav::Method::kOrca);
  EXPECT_STREQ(nav::MethodName(nav::Method::kOrca), "orca");
  const std::vector<nav::MethodSummary> s = nav::RunNavigation(c, dir.path(), 1);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].method, "orca");
  EXPECT_EQ(s[0].success_rate, 1.0) << "ORCA crosses a nearly empty square";
  EXPECT_EQ(s[0].robot_caused_doc_mean, 0.0);
  EXPECT_LE(s[0].robot_caused_doc_mean, s[0].doc_mean);
  // Its options are checked like the others', naming the key.
  c.orca.heading_gain = -1;
  testing::ExpectErrorContains([&] { c.Validate("cfg.yaml"); },
                               {"cfg.yaml", "orca", "heading_gain"});
}

TEST(NavigationRun, RobotCausedContactFollowsItsDefinition) {
  const Eigen::Vector2d robot(0, 0), ped(0.7, 0);  // overlapping: radius sum 0.8
  const double r = 0.8;
  // Driving into the pedestrian: the robot's fault.
  EXPECT_TRUE(nav::RobotCausedContact(robot, {0.5, 0}, ped, r, false));
  // Driving at 60 degrees off the normal: closing at 0.5 cos 60 = 0.25 m/s > 0.05: still.
  EXPECT_TRUE(nav::RobotCausedContact(robot, {0.25, 0.433}, ped, r, false));
  // Moving almost tangentially (closing at 0.04 m/s) or away: not.
  EXPECT_FALSE(nav::RobotCausedContact(robot, {0.04, 0.8}, ped, r, false));
  EXPECT_FALSE(nav::RobotCausedContact(robot, {-0.5, 0}, ped, r, false));
  // Standing still (|v| < 0.05) while run into: not, even with a tiny velocity toward it.
  EXPECT_FALSE(nav::RobotCausedContact(robot, {0.049, 0}, ped, r, false));
  // A pedestrian that just appeared inside the robot's disc: never.
  EXPECT_FALSE(nav::RobotCausedContact(robot, {0.5, 0}, ped, r, true));
  // No overlap: no contact at all.
  EXPECT_FALSE(nav::RobotCausedContact(robot, {0.5, 0}, {0.81, 0}, r, false));
  // Only the robot's own velocity counts (the pedestrian's is not an argument): the rule holds in
  // any frame orientation.
  const double a = 2.1;
  const Eigen::Vector2d turned(0.7 * std::cos(a), 0.7 * std::sin(a));
  EXPECT_TRUE(nav::RobotCausedContact(robot, 0.5 * turned.normalized(), turned, r, false));
  EXPECT_FALSE(nav::RobotCausedContact(robot, -0.5 * turned.normalized(), turned, r, false));
}

TEST(NavigationRun, WilsonIntervalMatchesHandComputedValues) {
  // (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n) with z = 1.96, n = 20.
  nav::RateInterval i = nav::WilsonInterval(0, 20);
  EXPECT_EQ(i.lo, 0.0);
  EXPECT_NEAR(i.hi, 0.161, 5e-4);
  i = nav::WilsonInterval(20, 20);
  EXPECT_NEAR(i.lo, 0.839, 5e-4);
  EXPECT_EQ(i.hi, 1.0);
  i = nav::WilsonInterval(10, 20);
  EXPECT_NEAR(i.lo, 0.299, 5e-4);
  EXPECT_NEAR(i.hi, 0.701, 5e-4);
  // k = 3, n = 40 by hand: centre (0.075 + 0.048020) / 1.096040 = 0.112241, half-width
  // 1.96 sqrt(0.0017344 + 0.00060025) / 1.096040 = 0.086405.
  i = nav::WilsonInterval(3, 40);
  EXPECT_NEAR(i.lo, 0.025836, 1e-5);
  EXPECT_NEAR(i.hi, 0.198646, 1e-5);
  // No episodes: no information.
  i = nav::WilsonInterval(0, 0);
  EXPECT_EQ(i.lo, 0.0);
  EXPECT_EQ(i.hi, 1.0);
}

TEST(NavigationRun, EpisodesAreDeterministicForReplayFreeMethods) {
  testing::TempDir dir;
  nav::ExperimentConfig c = SmallConfig(dir);
  c.methods = {"reactive"};
  const nav::Resources res = nav::PrepareNavigation(c, dir.path());
  const nav::EpisodeResult a = nav::RunEpisode(c, res, nav::Method::kReactive, 0),
                           b = nav::RunEpisode(c, res, nav::Method::kReactive, 0);
  EXPECT_EQ(a.path, b.path);
  EXPECT_EQ(a.doc, b.doc);
}

TEST(NavigationRun, BadScenesAndArtifactsAreClearErrors) {
  testing::TempDir dir;
  nav::ExperimentConfig c = SmallConfig(dir);
  c.methods = {"reactive"};
  // A goal inside a wall.
  nav::ExperimentConfig bad = c;
  bad.scenario.walls = {{0, -6, 0, 6}};
  bad.scenario.robot_goal = {0.0, 4.5};
  testing::ExpectErrorContains([&] { nav::RunNavigation(bad, dir.path(), 1); }, {"robot_goal"});
  // A wall across the whole square: the goal is unreachable.
  bad.scenario.robot_goal = {4.5, 4.5};
  testing::ExpectErrorContains([&] { nav::RunNavigation(bad, dir.path(), 1); },
                               {"robot_goal", "unreachable"});
  // A start in collision with the border.
  bad = c;
  bad.scenario.robot_start = {-5.9, -4.5, 0};
  testing::ExpectErrorContains([&] { nav::RunNavigation(bad, dir.path(), 1); }, {"robot_start"});
  // No pedestrians in a simulated scene.
  bad = c;
  bad.scenario.groups.clear();
  EXPECT_THROW(nav::RunNavigation(bad, dir.path(), 1), Error);
  // A map artifact where the predictor belongs, and the predictor where the map belongs.
  bad = c;
  bad.methods = {"span"};
  nav::RunNavigation(c, dir.path(), 1);  // writes map.h5
  bad.predictor.artifact = dir.File("map.h5");
  testing::ExpectErrorContains([&] { nav::PrepareNavigation(bad, dir.path()); },
                               {"map.h5", "span_predictor"});
  bad = c;
  bad.map.artifact = c.predictor.artifact;
  EXPECT_THROW(nav::PrepareNavigation(bad, dir.path()), Error);
  // A predictor that observes every 0.15 s cannot be fed at dt = 0.1 s.
  bad = c;
  bad.methods = {"span"};
  testing::RandomSpanSpec spec;
  spec.observed = 5;
  spec.seconds_per_step = 0.15;
  bad.predictor.artifact = dir.File("odd.h5");
  testing::WriteRandomSpanArtifact(bad.predictor.artifact, spec);
  testing::ExpectErrorContains([&] { nav::PrepareNavigation(bad, dir.path()); },
                               {"odd.h5", "multiple of dt"});
  bad = c;
  bad.methods = {"teleport"};
  testing::ExpectErrorContains([&] { nav::PrepareNavigation(bad, dir.path()); },
                               {"methods", "teleport"});
}

TEST(NavigationRun, SummaryMetricsFollowTheirDefinitions) {
  auto episode = [](bool reached, double ttg, double doc, double clear, std::vector<double> ms,
                    double robot_doc = 0) {
    nav::EpisodeResult r;
    r.method = "span";
    r.reached = reached;
    r.ttg = ttg;
    r.doc = doc;
    r.robot_caused_doc = robot_doc;
    r.min_clearance = clear;
    r.cycle_ms = std::move(ms);
    return r;
  };
  std::vector<nav::EpisodeResult> results = {episode(true, 20, 0.0, 0.2, {1, 2, 3}),
                                             episode(false, 90, 0.5, -0.1, {4, 5}, 0.3),
                                             episode(true, 30, 0.2, 0.05, {6})};
  results.push_back(results[0]);
  results.back().method = "reactive";  // other methods are not mixed in
  const nav::MethodSummary m = nav::Summarise("span", results);
  EXPECT_EQ(m.episodes, 3);
  EXPECT_DOUBLE_EQ(m.success_rate, 2.0 / 3);
  EXPECT_DOUBLE_EQ(m.collision_free_rate, 1.0 / 3);
  EXPECT_DOUBLE_EQ(m.ttg_mean, 25.0);  // reached episodes only
  EXPECT_DOUBLE_EQ(m.doc_mean, 0.7 / 3);
  EXPECT_DOUBLE_EQ(m.min_clearance, -0.1);
  EXPECT_DOUBLE_EQ(m.min_clearance_mean, 0.15 / 3);
  EXPECT_DOUBLE_EQ(m.cycle_ms_median, 3.5);  // of {1, ..., 6}
  EXPECT_NEAR(m.cycle_ms_p99, 5.95, 1e-12);  // linear interpolation at 0.99 * 5
  EXPECT_DOUBLE_EQ(m.cycle_ms_max, 6.0);
  // Success counts only with DOC = 0; TTG censored: the failure counts as its max_time (90 s).
  EXPECT_EQ(m.successes, 2);
  EXPECT_EQ(m.collision_free, 1);
  EXPECT_EQ(m.success_and_collision_free, 1);
  EXPECT_DOUBLE_EQ(m.success_and_collision_free_rate, 1.0 / 3);
  EXPECT_DOUBLE_EQ(m.ttg_censored_mean, (20.0 + 90.0 + 30.0) / 3);
  EXPECT_DOUBLE_EQ(m.robot_caused_doc_mean, 0.1);
  EXPECT_EQ(m.robot_caused_collision_free, 2);  // the 0.2 s of DOC in episode 3 were not caused
  EXPECT_DOUBLE_EQ(m.robot_caused_collision_free_rate, 2.0 / 3);
  EXPECT_EQ(m.success_rate_ci.lo, nav::WilsonInterval(2, 3).lo);
  EXPECT_EQ(m.success_and_collision_free_rate_ci.hi, nav::WilsonInterval(1, 3).hi);
  EXPECT_EQ(m.robot_caused_collision_free_rate_ci.hi, nav::WilsonInterval(2, 3).hi);
  // No controller reported a time-to-collision: the blocked share is unknown, not 0.
  EXPECT_TRUE(std::isnan(m.blocked_cycle_share));
  EXPECT_TRUE(std::isnan(m.stopped_time_share));  // no simulated time recorded
  // Blocked cycles over the cycles that reported one; stopped time over the episodes' durations.
  results[0].tau_cycles = 10, results[0].blocked_cycles = 4, results[0].stopped_time = 5;
  results[1].tau_cycles = 30, results[1].blocked_cycles = 6, results[1].stopped_time = 9;
  results[0].duration = 20, results[1].duration = 90, results[2].duration = 30;
  results[0].cycles = 200, results[1].cycles = 900, results[2].cycles = 300;
  results[0].fallback_cycles = 7, results[2].fallback_cycles = 3;
  const nav::MethodSummary b = nav::Summarise("span", results);
  EXPECT_DOUBLE_EQ(b.fallback_cycle_share, 10.0 / 1400);
  EXPECT_DOUBLE_EQ(b.blocked_cycle_share, 10.0 / 40);
  EXPECT_DOUBLE_EQ(b.stopped_time_share, 14.0 / (20 + 90 + 30));
  // None reached: TTG is null in the JSON, never NaN.
  nav::ExperimentConfig c;
  c.scenario.name = "a\"b";
  const std::string json =
      nav::SummaryJson(c, 1, {nav::Summarise("span", {episode(false, 90, 0, 0.1, {1})})});
  EXPECT_NE(json.find("\"ttg_mean\": null"), std::string::npos) << json;
  EXPECT_EQ(json.find("nan"), std::string::npos);
  EXPECT_EQ(json.find("inf"), std::string::npos);
  EXPECT_NE(json.find("\"a\\\"b\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"success_rate_ci\": [0, 0.793"), std::string::npos) << json;
  EXPECT_NE(json.find("\"ttg_censored_mean\": 90"), std::string::npos) << json;
}

}  // namespace
}  // namespace foresight
