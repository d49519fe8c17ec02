#include "datasets/crowd_sim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <random>

#include "datasets/data_root.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

/// d/dx of f at x by central differences (the shared helper, in 2-D).
Eigen::Vector2d Gradient(const std::function<double(const Eigen::Vector2d&)>& f,
                         const Eigen::Vector2d& x, double h = 1e-6) {
  return testing::CentralGradient([&](const Eigen::VectorXd& v) { return f(Eigen::Vector2d(v)); },
                                  x, h);
}

/// A simulated scenario of single pedestrians (one-way) from `starts` to `goals`, no robot walls.
CrowdScenarioConfig Singles(const std::vector<Eigen::Vector2d>& starts,
                            const std::vector<Eigen::Vector2d>& goals, double speed,
                            PowerLawParams params = PowerLawParams{}) {
  CrowdScenarioConfig s;
  s.name = "test";
  s.extent = {-20, 20, -20, 20};
  s.power_law = params;
  s.robot_start = {-19, -19, 0};
  s.robot_goal = {19, 19};
  for (std::size_t i = 0; i < starts.size(); ++i) {
    PedestrianGroupConfig g;
    g.count = 1;
    g.spawn = {starts[i].x(), starts[i].x(), starts[i].y(), starts[i].y()};
    g.goal = {goals[i].x(), goals[i].x(), goals[i].y(), goals[i].y()};
    g.preferred_speed = speed;
    g.speed_jitter = 0;
    g.round_trip = false;
    s.groups.push_back(g);
  }
  return s;
}

RobotAgent NoRobot() {
  RobotAgent r;
  r.present = false;
  return r;
}

/// Runs until every one-way pedestrian arrived or `max_time`; returns the time and the smallest gap
/// |x_i - x_j| - (r_i + r_j) seen (negative = overlap).
struct RunResult {
  double time = 0, min_gap = 1e9;
  bool all_arrived = false;
  std::vector<double> arrival;
};
RunResult RunCrowd(PowerLawCrowd* crowd, double max_time, const RobotAgent& robot = NoRobot(),
                   double dt = 0.1) {
  RunResult r;
  const auto n = crowd->agents().size();
  r.arrival.assign(n, -1);
  while (crowd->time() < max_time) {
    crowd->Step(dt, robot);
    const auto& a = crowd->agents();
    for (std::size_t i = 0; i < n; ++i) {
      if (r.arrival[i] < 0 && crowd->arrived(static_cast<int>(i))) r.arrival[i] = crowd->time();
      for (std::size_t j = i + 1; j < n; ++j)
        r.min_gap =
            std::min(r.min_gap, (a[i].position - a[j].position).norm() - a[i].radius - a[j].radius);
    }
    bool all = true;
    for (std::size_t i = 0; i < n; ++i) all = all && crowd->arrived(static_cast<int>(i));
    if (all) {
      r.all_arrived = true;
      break;
    }
  }
  r.time = crowd->time();
  return r;
}

TEST(PowerLaw, TimeToCollisionClosedForms) {
  // Head-on at closing speed 2 m/s, gap 5 - 1 = 4 m: tau = 2 s.
  EXPECT_NEAR(TimeToCollision({-5, 0}, {2, 0}, 1.0), 2.0, 1e-12);
  // Offset 0.6 < r = 1: |x + v t|^2 = 1 at (5 - 2t)^2 = 1 - 0.36.
  EXPECT_NEAR(TimeToCollision({-5, 0.6}, {2, 0}, 1.0), (5 - std::sqrt(0.64)) / 2, 1e-12);
  EXPECT_TRUE(std::isinf(TimeToCollision({-5, 1.2}, {2, 0}, 1.0)));  // passes by
  EXPECT_TRUE(std::isinf(TimeToCollision({-5, 0}, {-2, 0}, 1.0)));   // separating
  EXPECT_TRUE(std::isinf(TimeToCollision({-5, 0}, {0, 0}, 1.0)));    // no relative motion
  EXPECT_EQ(TimeToCollision({-0.5, 0}, {1, 0}, 1.0), 0.0);           // overlapping and approaching
  EXPECT_DOUBLE_EQ(PowerLawEnergy(2.0, 1.5, 2.0, 3.0), 1.5 / 4.0 * std::exp(-2.0 / 3.0));
  EXPECT_EQ(PowerLawEnergy(std::numeric_limits<double>::infinity(), 1.5, 2, 3), 0.0);
}

TEST(PowerLaw, InteractionForceIsMinusTheGradientOfTheEnergy) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0;
  for (const PowerLawParams& p : {PowerLawParams{}, PowerLawParams::Aggressive()}) {
    for (int trial = 0; trial < 2000; ++trial) {
      const Eigen::Vector2d x(4 * u(rng), 4 * u(rng)), v(1.5 * u(rng), 1.5 * u(rng));
      const double r = 0.8;
      const double tau = TimeToCollision(x, v, r);
      if (!std::isfinite(tau) || tau < 2 * p.tau_min || x.norm() < r + 0.05) continue;
      // Skip near-grazing configurations where tau(x) is not smooth at the FD step.
      const double a = v.squaredNorm(), b = x.dot(v), d = b * b - a * (x.squaredNorm() - r * r);
      if (d < 1e-3) continue;
      const auto energy = [&](const Eigen::Vector2d& y) {
        return PowerLawEnergy(TimeToCollision(y, v, r), p.k, p.exponent, p.tau0);
      };
      const Eigen::Vector2d fd = -Gradient(energy, x);
      const Eigen::Vector2d f = PowerLawInteractionForce(x, v, r, p.k, p);
      EXPECT_LT((f - fd).norm(), 1e-5 * (1 + fd.norm()))
          << "x " << x.transpose() << " v " << v.transpose();
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
  // Head-on: the force pushes i back along x (away from j), no sideways component.
  const Eigen::Vector2d f = PowerLawInteractionForce({-3, 0}, {1, 0}, 0.8, 1.5, PowerLawParams{});
  EXPECT_LT(f.x(), 0);
  EXPECT_NEAR(f.y(), 0, 1e-12);
  EXPECT_EQ(PowerLawInteractionForce({-3, 0}, {-1, 0}, 0.8, 1.5, PowerLawParams{}).norm(), 0.0);
}

TEST(PowerLaw, WallForceIsMinusTheGradientOfTheWallEnergy) {
  const PowerLawParams p;
  const SimWall w{{0, -2}, {0, 2}, 0.1};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int body = 0, ends = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const Eigen::Vector2d x(-1.5 + u(rng), 3 * u(rng)), v(1.5 * u(rng), 1.5 * u(rng));
    const double r = 0.4;
    const double tau = WallTimeToCollision(x, v, r, w);
    if (!std::isfinite(tau) || tau < 2 * p.tau_min ||
        DistanceToSegment(x, w.p, w.q) < r + w.half_thickness + 0.05)
      continue;
    const auto energy = [&](const Eigen::Vector2d& y) {
      return PowerLawEnergy(WallTimeToCollision(y, v, r, w), p.wall_k, p.exponent, p.tau0);
    };
    // Skip points where the candidate (body vs end cap) switches within the FD step.
    const Eigen::Vector2d fd = -Gradient(energy, x, 1e-7);
    const Eigen::Vector2d fd2 = -Gradient(energy, x, 1e-6);
    if ((fd - fd2).norm() > 1e-4 * (1 + fd.norm())) continue;
    const Eigen::Vector2d f = WallInteractionForce(x, v, r, w, p);
    EXPECT_LT((f - fd).norm(), 1e-4 * (1 + fd.norm()))
        << "x " << x.transpose() << " v " << v.transpose();
    const Eigen::Vector2d hit = x + v * tau;
    (std::abs(hit.y()) < 2 ? body : ends)++;
  }
  EXPECT_GT(body, 20);
  EXPECT_GT(ends, 5);
  EXPECT_NEAR(WallTimeToCollision({-2, 0}, {1, 0}, 0.4, w), 1.5, 1e-12);  // 2 - 0.4 - 0.1 at 1 m/s
}

// A preferred speed above the simulator's cap (1 m/s) would be cut silently: refused instead.
TEST(PowerLawCrowd, LoneAgentWalksStraightAtItsPreferredSpeedAndFasterOnesAreRefused) {
  for (const double speed : {0.8, 1.0}) {
    PowerLawCrowd crowd(Singles({{-10, 1}}, {{10, 1}}, speed, PowerLawParams::Aggressive()), 1);
    crowd.Step(3.0, NoRobot());  // relaxed after ~10 relaxation times
    const CrowdAgent& a = crowd.agents()[0];
    EXPECT_NEAR(a.velocity.norm(), speed, 1e-4) << speed;  // e^-10 left of the relaxation
    EXPECT_NEAR(a.position.y(), 1.0, 1e-9);
    EXPECT_NEAR(a.velocity.y(), 0.0, 1e-9);
    crowd.Step(5.0, NoRobot());
    EXPECT_NEAR(crowd.agents()[0].position.x(), -10 + 8 * speed - speed * 0.3, 0.05) << speed;
  }
  testing::ExpectErrorContains(
      [] {
        PowerLawCrowd(Singles({{-10, 1}}, {{10, 1}}, 1.6, PowerLawParams::Aggressive()), 1);
      },
      {"'groups[0].preferred_speed' = 1.6", "max_speed = 1"});
}

TEST(PowerLawCrowd, TwoAgentsHeadOnAvoidEachOtherAndArrive) {
  for (const PowerLawParams& p : {PowerLawParams{}, PowerLawParams::Aggressive()}) {
    PowerLawCrowd crowd(Singles({{-6, 0}, {6, 0.05}}, {{6, 0}, {-6, 0.05}}, 1.0, p), 2);
    double max_dev = 0;
    RunResult r;
    r.min_gap = 1e9;
    while (crowd.time() < 30 && !(crowd.arrived(0) && crowd.arrived(1))) {
      crowd.Step(0.1, NoRobot());
      const auto& a = crowd.agents();
      r.min_gap = std::min(r.min_gap, (a[0].position - a[1].position).norm() - 0.8);
      max_dev = std::max(max_dev, std::abs(a[0].position.y()));
    }
    EXPECT_TRUE(crowd.arrived(0) && crowd.arrived(1)) << "tau0 " << p.tau0;
    EXPECT_GT(r.min_gap, -0.05) << "tau0 " << p.tau0;
    EXPECT_GT(max_dev, 0.3) << "tau0 " << p.tau0;  // they swerve
    EXPECT_LT(crowd.time(), 12.0 / 1.0 * 1.4);
  }
}

TEST(PowerLawCrowd, PedestriansReactToTheRobot) {
  const CrowdScenarioConfig s = Singles({{-6, 0}}, {{6, 0}}, 1.0, PowerLawParams::Aggressive());
  RobotAgent robot;
  robot.position = {4, 0.1};
  robot.velocity = {-0.8, 0};
  robot.radius = 0.4;
  PowerLawCrowd with(s, 1), without(s, 1);
  double dev_with = 0, dev_without = 0, min_gap = 1e9;
  for (int k = 0; k < 80; ++k) {
    with.Step(0.1, robot);
    without.Step(0.1, NoRobot());
    robot.position += 0.1 * robot.velocity;
    dev_with = std::max(dev_with, std::abs(with.agents()[0].position.y()));
    dev_without = std::max(dev_without, std::abs(without.agents()[0].position.y()));
    min_gap = std::min(min_gap, (with.agents()[0].position - robot.position).norm() - 0.8);
  }
  EXPECT_LT(dev_without, 1e-9);
  EXPECT_GT(dev_with, 0.3);
  EXPECT_GT(min_gap, -0.05);
}

TEST(PowerLawCrowd, WallsAreNotCrossed) {
  CrowdScenarioConfig s =
      Singles({{-3, 0}, {-3, 2.5}}, {{5, 0.5}, {5, 2.5}}, 1.0, PowerLawParams::Aggressive());
  s.walls = {{0, -20, 0, 20}};  // a full partition: the goals are unreachable
  s.wall_thickness = 0.2;
  PowerLawCrowd crowd(s, 4);
  double max_x = -1e9;
  for (int k = 0; k < 200; ++k) {
    crowd.Step(0.1, NoRobot());
    for (const auto& a : crowd.agents()) max_x = std::max(max_x, a.position.x());
  }
  EXPECT_LE(max_x, -0.5 + 1e-9);  // radius 0.4 + half thickness 0.1
  EXPECT_GT(max_x, -0.6);         // and they do push against it
  // The extent's border is a wall as well.
  PowerLawCrowd out(Singles({{18, 0}}, {{19.9, 0}}, 1.0), 1);
  for (int k = 0; k < 50; ++k) out.Step(0.1, NoRobot());
  EXPECT_LE(out.agents()[0].position.x(), 20 - 0.4 + 1e-9);
}

TEST(PowerLawCrowd, DoorwayIsPassedWithoutTouchingTheWalls) {
  CrowdScenarioConfig s = Singles({{-4, 2}}, {{4, -2}}, 1.0, PowerLawParams::Aggressive());
  s.walls = {{0, -20, 0, -0.7}, {0, 0.7, 0, 20}};
  PowerLawCrowd crowd(s, 1);
  double min_clear = 1e9;
  while (crowd.time() < 30 && !crowd.arrived(0)) {
    crowd.Step(0.1, NoRobot());
    const Eigen::Vector2d x = crowd.agents()[0].position;
    for (const auto& w : s.walls)
      min_clear = std::min(min_clear, DistanceToSegment(x, {w.x0, w.y0}, {w.x1, w.y1}) - 0.4 - 0.1);
  }
  EXPECT_TRUE(crowd.arrived(0));
  EXPECT_GT(min_clear, -1e-9);
}

TEST(PowerLawCrowd, DeterministicInTheSeedAndSpawnsWithoutOverlap) {
  const CrowdScenarioConfig s = Sim1Scenario();
  PowerLawCrowd a(s, 11), b(s, 11), c(s, 12);
  ASSERT_EQ(a.agents().size(), 24u);
  for (std::size_t i = 0; i < a.agents().size(); ++i)
    for (std::size_t j = i + 1; j < a.agents().size(); ++j)
      EXPECT_GE((a.agents()[i].position - a.agents()[j].position).norm(), 0.8);
  RobotAgent robot;
  robot.position = {-9, 0};
  for (int k = 0; k < 30; ++k) {
    a.Step(0.1, robot);
    b.Step(0.1, robot);
    c.Step(0.1, robot);
  }
  double diff_same = 0, diff_other = 0;
  for (std::size_t i = 0; i < a.agents().size(); ++i) {
    diff_same += (a.agents()[i].position - b.agents()[i].position).norm();
    diff_other += (a.agents()[i].position - c.agents()[i].position).norm();
  }
  EXPECT_EQ(diff_same, 0.0);
  EXPECT_GT(diff_other, 1.0);
}

TEST(PowerLawCrowd, OvercrowdedSpawnBoxIsAnError) {
  CrowdScenarioConfig s = Singles({{0, 0}}, {{5, 5}}, 1.0);
  s.groups[0].count = 20;
  s.groups[0].spawn = {0, 1, 0, 1};
  testing::ExpectErrorContains([&] { PowerLawCrowd c(s, 1); },
                               {"groups[0]", "cannot place pedestrian", "spawn box"});
  s.groups[0].count = 1;
  s.groups[0].spawn = {0, 1};
  testing::ExpectErrorContains([&] { PowerLawCrowd c(s, 1); }, {"'groups[0].spawn'", "4 finite"});
}

// ---- the Implicit Crowds reference scenarios (../shared/data) -------------------------------
std::string ImplicitCrowdsDir() {
  std::vector<std::filesystem::path> roots;
  if (const char* data = std::getenv("FORESIGHT_DATA")) roots.emplace_back(data);
  if (const std::string shared = testing::SharedDataDir(); !shared.empty())
    roots.emplace_back(shared);
  for (const auto& root : roots) {
    const auto dir = root / "crowd_scenarios_implicit_crowds";
    if (std::filesystem::exists(dir / "8_agents.csv")) return dir.string();
  }
  return "";
}

// Found by review with fuzz_crowd_replay (tests/fuzz/corpus/crowd_replay/
// regress_huge_agent_count): the largest agent count overflowed 3 + count (undefined behaviour).
TEST(ImplicitCrowds, HugeAgentCountIsAnError) {
  testing::TempDir dir;
  const std::string path = dir.File("huge.csv");
  testing::WriteText(path, "-15 15\n-10 10\n9223372036854775807\n0 -9 -1 9 -1 1.3 0.75\n");
  testing::ExpectErrorContains([&] { ReadImplicitCrowdsScenario(path); },
                               {path, "announces 9223372036854775807 agents", "has 1 agent lines"});
}

TEST(ImplicitCrowds, ReaderParsesTheFormatAndRejectsBadFiles) {
  testing::TempDir dir;
  const std::string path = dir.File("two.csv");
  testing::WriteText(path,
                     "-15 15\r\n-10 10\r\n2\r\n0 -9 -1 9 -1 1.3 0.75\r\n1 9 1 -9 1 1.2 0.75\r\n");
  const CrowdScenarioConfig s = ReadImplicitCrowdsScenario(path);
  EXPECT_EQ(s.extent, (std::vector<double>{-15, 15, -10, 10}));
  ASSERT_EQ(s.groups.size(), 2u);
  EXPECT_EQ(s.groups[1].spawn, (std::vector<double>{9, 9, 1, 1}));
  EXPECT_EQ(s.groups[1].goal, (std::vector<double>{-9, -9, 1, 1}));
  EXPECT_DOUBLE_EQ(s.groups[1].preferred_speed, 1.2);
  EXPECT_DOUBLE_EQ(s.groups[1].radius, 0.75);
  EXPECT_FALSE(s.groups[1].round_trip);
  EXPECT_DOUBLE_EQ(s.power_law.max_speed, 1.5 * 1.3);
  testing::WriteText(path, "-15 15\n-10 10\n3\n0 -9 -1 9 -1 1.3 0.75\n");
  testing::ExpectErrorContains([&] { ReadImplicitCrowdsScenario(path); }, {path, "announces 3"});
  testing::WriteText(path, "-15 15\n-10 10\n1\n0 -9 nan 9 -1 1.3 0.75\n");
  testing::ExpectErrorContains([&] { ReadImplicitCrowdsScenario(path); }, {path + ":4", "'nan'"});
  testing::WriteText(path, "-15 15\n-10 10\n1\n0 -9 1 9 -1 1.3\n");
  testing::ExpectErrorContains([&] { ReadImplicitCrowdsScenario(path); },
                               {path + ":4", "expected 7 fields"});
  testing::WriteText(path, "-15 15\n-10 10\n1\n0 -99 1 9 -1 1.3 0.5\n");
  testing::ExpectErrorContains([&] { ReadImplicitCrowdsScenario(path); },
                               {"groups[0].spawn", "extent"});
  const std::string ini = dir.File("p.ini");
  testing::WriteText(ini, "k=2\r\np=3.25\nt0=2.5\nksi=2\nneighborDist=7\n");
  const PowerLawParams p = ReadImplicitCrowdsParameters(ini, PowerLawParams{});
  EXPECT_DOUBLE_EQ(p.k, 2);
  EXPECT_DOUBLE_EQ(p.exponent, 3.25);
  EXPECT_DOUBLE_EQ(p.tau0, 2.5);
  EXPECT_DOUBLE_EQ(p.neighbor_dist, 7);
  EXPECT_DOUBLE_EQ(p.relaxation, PowerLawParams{}.relaxation);  // ksi is not the relaxation time
  testing::WriteText(ini, "k=2\nfoo=1\n");
  testing::ExpectErrorContains([&] { ReadImplicitCrowdsParameters(ini, PowerLawParams{}); },
                               {ini + ":2", "'foo'"});
}

TEST(ImplicitCrowds, EightAgentsAntipodalCircleAllArriveWithoutCollision) {
  const std::string dir = ImplicitCrowdsDir();
  if (dir.empty())
    GTEST_SKIP()
        << "crowd_scenarios_implicit_crowds not found under $FORESIGHT_DATA or ../shared/data";
  const CrowdScenarioConfig base = ReadImplicitCrowdsScenario(dir + "/8_agents.csv");
  ASSERT_EQ(base.groups.size(), 8u);
  CrowdScenarioConfig with_ini = base;
  with_ini.power_law = ReadImplicitCrowdsParameters(dir + "/implicit.ini", base.power_law);
  for (const CrowdScenarioConfig& s : {base, with_ini}) {
    PowerLawCrowd crowd(s, 23);
    double straight = 0;  // the slowest agent's straight-line time
    for (std::size_t i = 0; i < s.groups.size(); ++i) {
      const auto& g = s.groups[i];
      straight = std::max(
          straight, std::hypot(g.goal[0] - g.spawn[0], g.goal[2] - g.spawn[2]) / g.preferred_speed);
    }
    const RunResult r = RunCrowd(&crowd, 4 * straight);
    EXPECT_TRUE(r.all_arrived) << "exponent " << s.power_law.exponent;
    EXPECT_GT(r.min_gap, -0.1) << "exponent " << s.power_law.exponent;
    EXPECT_LT(r.time, 1.6 * straight) << "exponent " << s.power_law.exponent;
    std::cout << "[ implicit 8_agents exponent " << s.power_law.exponent << " ] all arrived after "
              << r.time << " s (straight-line " << straight << " s), min gap " << r.min_gap
              << " m\n";
  }
}

TEST(ImplicitCrowds, ThreeAgentsMakeRoomForTheHeadOnAgent) {
  const std::string dir = ImplicitCrowdsDir();
  if (dir.empty())
    GTEST_SKIP()
        << "crowd_scenarios_implicit_crowds not found under $FORESIGHT_DATA or ../shared/data";
  const CrowdScenarioConfig s = ReadImplicitCrowdsScenario(dir + "/3_agents.csv");
  ASSERT_EQ(s.groups.size(), 3u);
  // The file is mirror-symmetric about y = 0 (pair at y = +-1, the third agent on y = 0), and so is
  // the deterministic model: the pair splits and the third agent passes between them. Shifted by
  // 0.3 m off the axis, the third agent swerves as well (and the pair still opens most of the gap).
  for (const double shift : {0.0, 0.3}) {
    CrowdScenarioConfig sc = s;
    sc.groups[2].spawn[2] = sc.groups[2].spawn[3] = shift;
    sc.groups[2].goal[2] = sc.groups[2].goal[3] = shift;
    PowerLawCrowd crowd(sc, 23);
    double dev_single = 0, dev_pair = 0, min_gap = 1e9;
    while (crowd.time() < 40 && !(crowd.arrived(0) && crowd.arrived(1) && crowd.arrived(2))) {
      crowd.Step(0.2, NoRobot());  // the reference run's dt
      const auto& a = crowd.agents();
      dev_single = std::max(dev_single, std::abs(a[2].position.y() - shift));
      dev_pair = std::max({dev_pair, a[1].position.y() - 1.0, -1.0 - a[0].position.y()});
      for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
          min_gap =
              std::min(min_gap, (a[i].position - a[j].position).norm() - a[i].radius - a[j].radius);
    }
    EXPECT_TRUE(crowd.arrived(0) && crowd.arrived(1) && crowd.arrived(2)) << shift;
    EXPECT_GT(min_gap, -0.1) << shift;
    EXPECT_GT(dev_pair + dev_single, 0.5)
        << shift;  // room is made: 2 r = 1.5 m > the pair's 2 m gap - 1.5 m
    if (shift > 0) {
      EXPECT_GT(dev_single, 0.05);  // off the axis, the head-on agent swerves too
    }
    std::cout << "[ implicit 3_agents, third agent at y = " << shift << " ] its max deviation "
              << dev_single << " m, pair's max outward deviation " << dev_pair << " m, min gap "
              << min_gap << " m, all arrived after " << crowd.time() << " s\n";
  }
}

TEST(ImplicitCrowds, FourHundredCrossingAgentsStayFiniteAndApart) {
  const std::string dir = ImplicitCrowdsDir();
  if (dir.empty())
    GTEST_SKIP()
        << "crowd_scenarios_implicit_crowds not found under $FORESIGHT_DATA or ../shared/data";
  const CrowdScenarioConfig s = ReadImplicitCrowdsScenario(dir + "/crossing_agents.csv");
  ASSERT_EQ(s.groups.size(), 400u);
  PowerLawCrowd crowd(s, 23);
  for (int k = 0; k < 20; ++k) crowd.Step(0.2, NoRobot());
  const auto& a = crowd.agents();
  int overlaps = 0;
  double mean_speed = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_TRUE(a[i].position.allFinite());
    mean_speed += a[i].velocity.norm() / a.size();
    for (std::size_t j = i + 1; j < a.size(); ++j)
      overlaps += (a[i].position - a[j].position).norm() < 0.9 * (a[i].radius + a[j].radius);
  }
  EXPECT_LE(overlaps, 4);
  EXPECT_GT(mean_speed, 0.5);
  std::cout << "[ implicit crossing_agents ] after 4 s: mean speed " << mean_speed
            << " m/s, pairs overlapping > 10 %: " << overlaps << "\n";
}

}  // namespace
}  // namespace foresight
