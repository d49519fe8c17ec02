// Synthetic manipulation problems: deterministic for a seed, obstacles where the config promises,
// start and goal accepted by the caller's predicate, clear errors when none can be found.

#include "inference/manipulation/synthetic_problems.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/config.h"
#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

using testing::ExpectErrorContains;

JointVector PandaLower() {
  JointVector q;
  q << -2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973;
  return q;
}
JointVector PandaUpper() {
  JointVector q;
  q << 2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973;
  return q;
}

bool SameWorld(const World& a, const World& b) {
  if (a.num_obstacles() != b.num_obstacles()) return false;
  for (int i = 0; i < a.num_obstacles(); ++i) {
    const Obstacle &oa = a.obstacle(i), &ob = b.obstacle(i);
    if (oa.id != ob.id || oa.is_box() != ob.is_box()) return false;
    if (oa.is_box() ? !(oa.box().X_WB.matrix() == ob.box().X_WB.matrix() &&
                        oa.box().half_size == ob.box().half_size)
                    : !(oa.cylinder().X_WC.matrix() == ob.cylinder().X_WC.matrix() &&
                        oa.cylinder().radius == ob.cylinder().radius &&
                        oa.cylinder().half_height == ob.cylinder().half_height))
      return false;
  }
  return true;
}

TEST(SyntheticWorld, DeterministicForASeed) {
  const SyntheticSceneConfig config;
  const World a = MakeSyntheticWorld(config, 42);
  EXPECT_TRUE(SameWorld(a, MakeSyntheticWorld(config, 42)));
  EXPECT_FALSE(SameWorld(a, MakeSyntheticWorld(config, 43)));
  // 1 table (top + 4 legs), 1 shelf (2 sides + 2..4 boards), 3 boxes, 2 cans.
  EXPECT_GE(a.num_obstacles(), 5 + 4 + 3 + 2);
  EXPECT_LE(a.num_obstacles(), 5 + 6 + 3 + 2);
  EXPECT_EQ(a.num_cylinders(), 2);
  EXPECT_GE(a.FindObstacle("table0_top"), 0);
  EXPECT_GE(a.FindObstacle("table0_leg3"), 0);
  EXPECT_GE(a.FindObstacle("shelf0_side_left"), 0);
  EXPECT_GE(a.FindObstacle("shelf0_board1"), 0);
  EXPECT_GE(a.FindObstacle("box2"), 0);
  EXPECT_GE(a.FindObstacle("can1"), 0);
}

TEST(SyntheticWorld, ObstaclesStayWhereTheConfigPromises) {
  SyntheticSceneConfig config;
  config.tables = 2;
  config.shelves = 1;
  config.boxes = 6;
  config.cylinders = 4;
  const double a = config.max_azimuth_deg * M_PI / 180.0;
  for (std::uint64_t seed = 0; seed < 40; ++seed) {
    const World w = MakeSyntheticWorld(config, seed);
    std::vector<int> owner;
    const Eigen::Matrix3Xd pts = w.SurfacePoints(0.02, &owner);
    std::vector<double> nearest(static_cast<std::size_t>(w.num_obstacles()), 1e9);
    for (Eigen::Index k = 0; k < pts.cols(); ++k) {
      const double horizontal = pts.col(k).head<2>().norm();
      ASSERT_GE(horizontal, config.reach_min - 1e-9)
          << "seed " << seed << " obstacle " << w.obstacle(owner[k]).id;
      ASSERT_GE(pts(2, k), config.floor_z - 1e-9) << "seed " << seed;
      double& n = nearest[static_cast<std::size_t>(owner[static_cast<std::size_t>(k)])];
      n = std::min(n, horizontal);
    }
    for (int i = 0; i < w.num_obstacles(); ++i) {
      const Obstacle& o = w.obstacle(i);
      const Eigen::Vector3d c = o.is_box() ? Eigen::Vector3d(o.box().X_WB.translation())
                                           : Eigen::Vector3d(o.cylinder().X_WC.translation());
      const bool loose = o.id.rfind("box", 0) == 0 || o.id.rfind("can", 0) == 0;
      if (loose || o.id.find("_top") != std::string::npos ||
          o.id.find("_board") != std::string::npos) {
        EXPECT_LE(std::abs(std::atan2(c.y(), c.x())), a + 1e-12) << o.id;
      }
      if (loose) {  // centre within reach (or just far enough out to clear reach_min)
        const double bounding = o.is_box() ? o.box().half_size.norm() : o.cylinder().radius;
        EXPECT_LE(c.head<2>().norm(),
                  std::max(config.reach_max, config.reach_min + bounding) + 1e-12)
            << o.id;
      } else if (o.id.find("_top") != std::string::npos ||
                 o.id.find("_board") != std::string::npos) {
        // The base-facing edge is within reach (surface samples are 0.02 m apart).
        EXPECT_LE(nearest[static_cast<std::size_t>(i)], config.reach_max + 0.01) << o.id;
      }
    }
  }
}

TEST(SyntheticWorld, ConfigIsValidatedAndSerialised) {
  SyntheticSceneConfig bad;
  bad.reach_min = 0.9;
  ExpectErrorContains([&] { MakeSyntheticWorld(bad, 1); }, {"reach_min 0.9", "reach_max 0.8"});
  SyntheticSceneConfig low;
  low.floor_z = 0.0;
  ExpectErrorContains([&] { MakeSyntheticWorld(low, 1); }, {"table_height_min", "floor_z"});
  SyntheticSceneConfig empty;
  empty.tables = empty.shelves = empty.boxes = empty.cylinders = 0;
  EXPECT_EQ(MakeSyntheticWorld(empty, 1).num_obstacles(), 0);

  SyntheticSceneConfig c;
  c.boxes = 7;
  c.reach_max = 0.7;
  const SyntheticSceneConfig back = config::FromYaml<SyntheticSceneConfig>(
      config::ParseYaml(config::ToYaml(c), "<test>"), "<test>");
  EXPECT_EQ(back.boxes, 7);
  EXPECT_EQ(back.reach_max, 0.7);
  ExpectErrorContains(
      [] { config::FromYaml<SyntheticSceneConfig>(config::ParseYaml("tabels: 2", "<t>"), "<t>"); },
      {"tabels"});
}

TEST(SyntheticProblem, StartAndGoalSatisfyThePredicate) {
  const SyntheticSceneConfig scene;
  StartGoalConfig sampling;
  sampling.min_separation = 1.5;
  int calls = 0;
  const World* seen = nullptr;
  // A stand-in for the validity checker: joint 1 positive and the world non-empty.
  auto is_valid = [&](const World& world, const JointVector& q) {
    ++calls;
    seen = &world;
    return q(0) > 0.5 && world.num_obstacles() > 0;
  };
  const ManipulationProblem p =
      MakeSyntheticProblem(scene, sampling, PandaLower(), PandaUpper(), is_valid, 9);
  EXPECT_GT(calls, 1);
  EXPECT_GT(p.start(0), 0.5);
  EXPECT_GT(p.goal(0), 0.5);
  EXPECT_GE((p.goal - p.start).norm(), 1.5);
  EXPECT_TRUE((p.start.array() >= PandaLower().array()).all() &&
              (p.start.array() <= PandaUpper().array()).all());
  EXPECT_TRUE((p.goal.array() >= PandaLower().array()).all() &&
              (p.goal.array() <= PandaUpper().array()).all());
  EXPECT_EQ(p.family, "synthetic");
  EXPECT_NE(p.source.find("seed 9"), std::string::npos);
  EXPECT_TRUE(SameWorld(p.world, MakeSyntheticWorld(scene, 9)));
  EXPECT_NE(seen, nullptr);

  const ManipulationProblem again =
      MakeSyntheticProblem(scene, sampling, PandaLower(), PandaUpper(), is_valid, 9);
  EXPECT_EQ(again.start, p.start);
  EXPECT_EQ(again.goal, p.goal);
  const ManipulationProblem other =
      MakeSyntheticProblem(scene, sampling, PandaLower(), PandaUpper(), is_valid, 10);
  EXPECT_NE(other.start, p.start);
}

TEST(SyntheticProblem, ClearErrorsWhenNothingIsFound) {
  StartGoalConfig sampling;
  sampling.max_attempts = 50;
  int calls = 0;
  ExpectErrorContains(
      [&] {
        SampleStartGoal(
            PandaLower(), PandaUpper(),
            [&](const JointVector&) {
              ++calls;
              return false;
            },
            sampling, 5);
      },
      {"no valid start", "50 uniform draws", "seed 5", "rejected every one"});
  EXPECT_EQ(calls, 50);
  // Limits too narrow for the separation: every goal is too close.
  JointVector lo = JointVector::Zero(), hi = JointVector::Constant(0.1);
  sampling.min_separation = 1.0;
  ExpectErrorContains(
      [&] {
        SampleStartGoal(
            lo, hi, [](const JointVector&) { return true; }, sampling, 5);
      },
      {"no valid goal", "50 were closer than min_separation 1"});
  ExpectErrorContains(
      [&] {
        SampleStartGoal(
            hi, lo, [](const JointVector&) { return true; }, sampling, 5);
      },
      {"joint limits", "lower < upper"});
  const StartGoal ok = SampleStartGoal(
      PandaLower(), PandaUpper(), [](const JointVector& q) { return q(3) < -1.0; },
      StartGoalConfig{}, 5);
  EXPECT_LT(ok.start(3), -1.0);
  EXPECT_LT(ok.goal(3), -1.0);
  EXPECT_GE(ok.start_draws, 1);
}

}  // namespace
}  // namespace foresight::manipulation
