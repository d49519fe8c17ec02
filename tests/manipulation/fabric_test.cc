// The geometric fabric: each term's pull-back (x, J, J' q_d) against finite differences along a
// trajectory, the fused metric (symmetric, positive definite), energisation (speed-preserving
// geometry), rollouts (reach the command, never penetrate, statuses for bad states) and the
// GFCOP cost and solver (thesis ch 9).

#include "inference/manipulation/fabric.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <utility>

#include "core/error.h"
#include "inference/manipulation/builtin_panda.h"
#include "inference/manipulation/gfcs.h"
#include "inference/manipulation/synthetic_problems.h"
#include "inference/manipulation/validity.h"

namespace foresight::manipulation {
namespace {

const RobotModel& Panda() {
  static const RobotModel robot = BuiltinPanda();
  return robot;
}

JointVector RandomConfiguration(std::mt19937_64* rng) {
  const JointLimits& l = Panda().limits();
  std::uniform_real_distribution<double> unit(0, 1);
  JointVector q;
  for (int j = 0; j < kDof; ++j)
    q[j] = l.lower[j] + 0.1 + unit(*rng) * (l.upper[j] - l.lower[j] - 0.2);
  return q;
}

JointVector RandomVector(std::mt19937_64* rng, double scale) {
  std::normal_distribution<double> normal(0, scale);
  JointVector v;
  for (int j = 0; j < kDof; ++j) v[j] = normal(*rng);
  return v;
}

/// One box in front of the robot and one upright cylinder beside it.
World TwoObstacleWorld() {
  World world;
  Box box;
  box.X_WB.translation() = Eigen::Vector3d(0.55, 0.0, 0.35);
  box.X_WB.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  box.half_size = Eigen::Vector3d(0.1, 0.25, 0.02);
  world.AddBox("shelf", box);
  Cylinder cyl;
  cyl.X_WC.translation() = Eigen::Vector3d(0.3, 0.45, 0.4);
  cyl.radius = 0.04;
  cyl.half_height = 0.15;
  world.AddCylinder("can", cyl);
  return world;
}

/// x(t) of a task along q(t) = q + v t + a t^2 / 2; checks x_d = J v and x_dd = J a + J' v by
/// central differences (the curvature J' q_d is what the fabric subtracts).
template <class TaskAt>
void ExpectPullBackMatchesFiniteDifferences(const TaskAt& task_at, const JointVector& q,
                                            const JointVector& v, const JointVector& a) {
  const double h = 1e-4;
  const auto x = [&](double t) { return task_at(q + v * t + 0.5 * a * t * t, v + a * t).x; };
  const ScalarTask t0 = task_at(q, v);
  const double xd_fd = (x(h) - x(-h)) / (2 * h);
  const double xdd_fd = (x(h) - 2 * x(0) + x(-h)) / (h * h);
  EXPECT_NEAR(t0.xd, (t0.J * v)(0), 1e-12);
  EXPECT_NEAR(t0.xd, xd_fd, 1e-6 * (1 + std::abs(xd_fd)));
  EXPECT_NEAR((t0.J * a)(0) + t0.jdq, xdd_fd, 2e-4 * (1 + std::abs(xdd_fd)));
}

TEST(FabricTerms, SphereObstacleTaskMatchesFiniteDifferences) {
  const World world = TwoObstacleWorld();
  KinematicsData data = Panda().MakeData();
  std::mt19937_64 rng(11);
  int checked = 0;
  for (int trial = 0; trial < 200 && checked < 40; ++trial) {
    const JointVector q = RandomConfiguration(&rng);
    const JointVector v = RandomVector(&rng, 0.8), a = RandomVector(&rng, 1.0);
    for (int s = 0; s < Panda().num_spheres(); s += 3) {
      const auto task_at = [&](const JointVector& qq, const JointVector& vv) {
        ForwardKinematicsWithJacobians(Panda(), qq, vv, &data);
        return SphereObstacleTask(world, data.p_WS.col(s), Panda().spheres()[s].radius,
                                  data.J_WS[s], data.Jdot_qdot_WS[s], vv);
      };
      const ScalarTask t = task_at(q, v);
      if (t.x <= 0.01 || t.x > 0.3) continue;  // the terms act within range, outside obstacles
      SCOPED_TRACE(testing::Message() << "trial " << trial << " sphere " << s << " x " << t.x);
      ExpectPullBackMatchesFiniteDifferences(task_at, q, v, a);
      ++checked;
    }
  }
  EXPECT_GE(checked, 20);
}

TEST(FabricTerms, SpherePairTaskMatchesFiniteDifferences) {
  KinematicsData data = Panda().MakeData();
  std::mt19937_64 rng(12);
  const auto& pairs = Panda().self_collision_pairs();
  ASSERT_FALSE(pairs.empty());
  for (int trial = 0; trial < 30; ++trial) {
    const JointVector q = RandomConfiguration(&rng);
    const JointVector v = RandomVector(&rng, 0.8), a = RandomVector(&rng, 1.0);
    const auto [i, j] = pairs[static_cast<std::size_t>(trial * 7919) % pairs.size()];
    const auto task_at = [&, i = i, j = j](const JointVector& qq, const JointVector& vv) {
      ForwardKinematicsWithJacobians(Panda(), qq, vv, &data);
      return SpherePairTask(data.p_WS.col(i), Panda().spheres()[i].radius, data.J_WS[i],
                            data.Jdot_qdot_WS[i], data.p_WS.col(j), Panda().spheres()[j].radius,
                            data.J_WS[j], data.Jdot_qdot_WS[j], vv);
    };
    SCOPED_TRACE(testing::Message() << "pair " << i << "," << j);
    ExpectPullBackMatchesFiniteDifferences(task_at, q, v, a);
  }
}

TEST(FabricTerms, BarrierMetricIsOnOnlyWhileApproachingWithinRange) {
  const BarrierParams p{1.0, 0.5, 0.2};
  EXPECT_EQ(BarrierMetric(p, 0.1, 0.3), 0.0);     // moving away
  EXPECT_EQ(BarrierMetric(p, 0.25, -0.3), 0.0);   // beyond range
  EXPECT_EQ(BarrierMetric(p, -0.01, -0.3), 0.0);  // penetrating: the rollout stops instead
  EXPECT_NEAR(BarrierMetric(p, 0.1, -0.3), 0.5 * (1 / 0.1 - 1 / 0.2), 1e-15);
  EXPECT_NEAR(BarrierMetric(p, 0.2 - 1e-9, -0.3), 0.0, 1e-7);  // continuous at the range
}

TEST(Fabric, MetricIsSymmetricPositiveDefiniteAndGeometryKeepsTheSpeed) {
  const World world = TwoObstacleWorld();
  const Fabric fabric(Panda(), world, FabricParams{});
  FabricWorkspace ws = fabric.MakeWorkspace();
  std::mt19937_64 rng(13);
  int active = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const JointVector q = RandomConfiguration(&rng), qd = RandomVector(&rng, 1.0);
    JointVector qdd;
    if (!fabric.Acceleration(q, qd, RandomConfiguration(&rng), &ws, &qdd)) continue;
    const auto& M = ws.probe.metric;
    EXPECT_LT((M - M.transpose()).norm(), 1e-12 * M.norm());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, kDof, kDof>> eig(M);
    EXPECT_GE(eig.eigenvalues().minCoeff(), fabric.params().base_inertia * (1 - 1e-9));
    // Energised geometry: q_d' q_dd_e = 0 (the Euclidean kinetic energy is kept).
    EXPECT_NEAR(qd.dot(ws.probe.energized), 0.0, 1e-9 * (1 + ws.probe.energized.norm()));
    active += ws.probe.active_obstacle_terms + ws.probe.active_self_terms;
  }
  EXPECT_GT(active, 0) << "no barrier term was ever active: the test did not test them";
}

/// The Panda's ready pose and a goal the fabric reaches from it in an empty world.
std::pair<JointVector, JointVector> ReadyToReachPoses() {
  JointVector start, goal;
  start << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  goal << 0.8, 0.2, -0.3, -1.8, 0.4, 2.0, 0.2;
  return {start, goal};
}

TEST(Fabric, RolloutReachesTheCommandInAnEmptyWorld) {
  const World world;
  const Fabric fabric(Panda(), world, FabricParams{});
  FabricWorkspace ws = fabric.MakeWorkspace();
  const auto [start, goal] = ReadyToReachPoses();
  std::vector<JointVector> path;
  const RolloutResult r = fabric.Rollout(start, JointVector::Zero(), goal, &ws, &path);
  EXPECT_EQ(r.status, RolloutStatus::kReached) << ToString(r.status);
  EXPECT_LT((r.q - goal).norm(), fabric.params().goal_tolerance);
  EXPECT_GT(r.t, 0.1);
  EXPECT_LT(r.t, fabric.params().t_max);
  EXPECT_EQ(static_cast<int>(path.size()), r.steps);
  EXPECT_NEAR(r.t, r.steps * fabric.params().dt, 1e-12);
}

TEST(Fabric, AStoppedRolloutIsThePrefixOfTheFullOne) {
  const World world = TwoObstacleWorld();
  const Fabric fabric(Panda(), world, FabricParams{});
  FabricWorkspace ws = fabric.MakeWorkspace();
  const auto [start, goal] = ReadyToReachPoses();
  std::vector<JointVector> full_path;
  const RolloutResult full = fabric.Rollout(start, JointVector::Zero(), goal, &ws, &full_path);
  ASSERT_GT(full.steps, 10) << ToString(full.status);
  const double limit = 0.5 * full.t;
  std::vector<JointVector> path;
  const RolloutResult stopped = fabric.Rollout(start, JointVector::Zero(), goal, &ws, &path, limit);
  EXPECT_EQ(stopped.status, RolloutStatus::kStopped);
  EXPECT_GT(stopped.t, limit);  // the first step past the limit
  EXPECT_LE(stopped.t - fabric.params().dt, limit);
  ASSERT_EQ(static_cast<int>(path.size()), stopped.steps);
  for (int i = 0; i < stopped.steps; ++i) EXPECT_EQ(path[i], full_path[i]);
  EXPECT_EQ(stopped.q, full_path[stopped.steps - 1]);
  // A limit beyond the rollout changes nothing.
  const RolloutResult same =
      fabric.Rollout(start, JointVector::Zero(), goal, &ws, nullptr, full.t + 1.0);
  EXPECT_EQ(same.status, full.status);
  EXPECT_EQ(same.q, full.q);
  EXPECT_EQ(same.t, full.t);
}

TEST(Fabric, RolloutsNeverPenetrateTheObstacles) {
  const World world = TwoObstacleWorld();
  const Fabric fabric(Panda(), world, FabricParams{});
  const ValidityChecker checker(Panda(), world);
  FabricWorkspace ws = fabric.MakeWorkspace();
  KinematicsData data = Panda().MakeData();
  std::mt19937_64 rng(14);
  int rollouts = 0, collisions = 0;
  for (int trial = 0; trial < 200 && rollouts < 30; ++trial) {
    const JointVector start = RandomConfiguration(&rng), goal = RandomConfiguration(&rng);
    if (checker.Check(start, &data) != Validity::kValid ||
        checker.Check(goal, &data) != Validity::kValid)
      continue;
    std::vector<JointVector> path;
    const RolloutResult r = fabric.Rollout(start, JointVector::Zero(), goal, &ws, &path);
    ++rollouts;
    collisions += r.status == RolloutStatus::kCollision;
    if (r.status != RolloutStatus::kCollision) {
      for (const JointVector& q : path)
        ASSERT_NE(checker.Check(q, &data), Validity::kWorldCollision);
    }
  }
  EXPECT_EQ(rollouts, 30);
  // Measured with the default params (seed 14, built-in Panda): at most 1 of these 30; 3 of 100
  // in a longer run, all self-collisions.
  EXPECT_LE(collisions, 1) << "the barrier terms should keep the rollouts clear";
}

/// Rollouts in an empty world between random valid configurations that end in a collision (all
/// self-collisions, as nothing else is there).
int SelfCollisionsInFreeSpace(const FabricParams& params, int rollouts) {
  const World world;
  const Fabric fabric(Panda(), world, params);
  const ValidityChecker checker(Panda(), world);
  FabricWorkspace ws = fabric.MakeWorkspace();
  KinematicsData data = Panda().MakeData();
  std::mt19937_64 rng(21);
  int done = 0, collisions = 0;
  for (int trial = 0; trial < 20 * rollouts && done < rollouts; ++trial) {
    const JointVector start = RandomConfiguration(&rng), goal = RandomConfiguration(&rng);
    if (checker.Check(start, &data) != Validity::kValid ||
        checker.Check(goal, &data) != Validity::kValid)
      continue;
    ++done;
    collisions +=
        fabric.Rollout(start, JointVector::Zero(), goal, &ws).status == RolloutStatus::kCollision;
  }
  EXPECT_EQ(done, rollouts) << "too few valid random configurations";
  return collisions;
}

TEST(Fabric, SelfCollisionBarrierKeepsFreeSpaceRolloutsClear) {
  // The default self-collision term (gain 10, metric 5, range 0.05 m; experiments/
  // fabric_select.sh) against the earlier {1, 0.5, 0.03}, which let the arm fold into itself:
  // 100 free-space rollouts (seed 21), at most one collision with the default, more with the weak.
  FabricParams weak;
  weak.self = BarrierParams{1.0, 0.5, 0.03};
  const int with_default = SelfCollisionsInFreeSpace(FabricParams{}, 100);
  const int with_weak = SelfCollisionsInFreeSpace(weak, 100);
  EXPECT_LE(with_default, 1);
  EXPECT_GT(with_weak, with_default);
}

TEST(Fabric, NonFiniteStatesStopWithAStatus) {
  const World world = TwoObstacleWorld();
  const Fabric fabric(Panda(), world, FabricParams{});
  FabricWorkspace ws = fabric.MakeWorkspace();
  JointVector q = JointVector::Zero();
  q[3] = -1.5;
  JointVector bad = q;
  bad[2] = std::nan("");
  EXPECT_EQ(fabric.Rollout(bad, JointVector::Zero(), q, &ws).status, RolloutStatus::kNonFinite);
  EXPECT_EQ(fabric.Rollout(q, JointVector::Constant(INFINITY), q, &ws).status,
            RolloutStatus::kNonFinite);
  EXPECT_EQ(fabric.Rollout(q, JointVector::Zero(), bad, &ws).status, RolloutStatus::kNonFinite);
  JointVector qdd = JointVector::Constant(7);
  EXPECT_FALSE(fabric.Acceleration(bad, JointVector::Zero(), q, &ws, &qdd));
  EXPECT_EQ(qdd, JointVector::Constant(7));  // untouched
}

TEST(Fabric, RejectsInvalidParams) {
  const World world;
  FabricParams p;
  p.dt = 0;
  EXPECT_THROW(Fabric(Panda(), world, p), Error);
  p = FabricParams{};
  p.t_max = 0.001;
  EXPECT_THROW(Fabric(Panda(), world, p), Error);
  p = FabricParams{};
  p.stall_window = -1;
  EXPECT_THROW(Fabric(Panda(), world, p), Error);
  p = FabricParams{};
  p.stall_window = 1;
  p.stall_progress = 0;
  EXPECT_THROW(Fabric(Panda(), world, p), Error);
}

/// A synthetic problem of the generator with the built-in Panda.
ManipulationProblem SyntheticProblem(std::uint64_t seed) {
  const auto is_valid = [](const World& world, const JointVector& q) {
    const ValidityChecker checker(Panda(), world);
    KinematicsData data = Panda().MakeData();
    return checker.Check(q, &data) == Validity::kValid;
  };
  return MakeSyntheticProblem(SyntheticSceneConfig{}, StartGoalConfig{}, Panda().limits().lower,
                              Panda().limits().upper, is_valid, seed);
}

/// The problem's start (at rest) and goal.
GfcsQuery QueryOf(const ManipulationProblem& problem) {
  GfcsQuery query;
  query.start = problem.start;
  query.goal = problem.goal;
  return query;
}

/// The fused metric M and the energised geometry of `fabric` at (q, qd), summed over every sphere
/// and every checked pair with the world's full distance queries (no broad phase, no skipping).
struct FullSums {
  Eigen::Matrix<double, kDof, kDof> M;
  JointVector energized;
  double min_obstacle_clearance = std::numeric_limits<double>::infinity();
  double min_self_clearance = std::numeric_limits<double>::infinity();
};

FullSums SumEveryTerm(const Fabric& fabric, const JointVector& q, const JointVector& qd,
                      const JointVector& command) {
  const FabricParams& p = fabric.params();
  const RobotModel& robot = fabric.robot();
  KinematicsData kin = robot.MakeData();
  ForwardKinematicsWithJacobians(robot, q, qd, &kin);
  FullSums out;
  out.M = p.base_inertia * Eigen::Matrix<double, kDof, kDof>::Identity();
  JointVector f = JointVector::Zero();
  const auto add = [&](const BarrierParams& b, const ScalarTask& t) {
    const double m = BarrierMetric(b, t.x, t.xd);
    if (m == 0) return;
    out.M += m * t.J.transpose() * t.J;
    f += m * (b.gain * t.xd * t.xd / t.x - t.jdq) * t.J.transpose();
  };
  for (int j = 0; j < kDof; ++j) {
    ScalarTask lo, hi;
    lo.x = q[j] - robot.limits().lower[j];
    lo.xd = qd[j];
    lo.J(j) = 1;
    hi.x = robot.limits().upper[j] - q[j];
    hi.xd = -qd[j];
    hi.J(j) = -1;
    add(p.limits, lo);
    add(p.limits, hi);
  }
  const auto& spheres = robot.spheres();
  for (int s = 0; s < robot.num_spheres(); ++s) {
    const ScalarTask t = SphereObstacleTask(fabric.world(), kin.p_WS.col(s), spheres[s].radius,
                                            kin.J_WS[s], kin.Jdot_qdot_WS[s], qd);
    out.min_obstacle_clearance = std::min(out.min_obstacle_clearance, t.x);
    if (t.x > 0) add(p.obstacles, t);
  }
  for (const auto& [a, b] : robot.self_collision_pairs()) {
    const ScalarTask t =
        SpherePairTask(kin.p_WS.col(a), spheres[a].radius, kin.J_WS[a], kin.Jdot_qdot_WS[a],
                       kin.p_WS.col(b), spheres[b].radius, kin.J_WS[b], kin.Jdot_qdot_WS[b], qd);
    out.min_self_clearance = std::min(out.min_self_clearance, t.x);
    if (t.x > 0) add(p.self, t);
  }
  const double r = (q - command).norm(), w = p.attractor_metric_width;
  out.M.diagonal().array() +=
      p.attractor_metric_far +
      (p.attractor_metric_near - p.attractor_metric_far) * std::exp(-(r / w) * (r / w));
  out.energized = out.M.llt().solve(f);
  out.energized -= qd * (qd.dot(out.energized) / qd.squaredNorm());
  return out;
}

TEST(Fabric, TheBroadPhaseSkipsOnlySpheresAndPairsThatCannotAct) {
  int states = 0, obstacle_terms = 0, self_terms = 0, queries = 0, pairs = 0, near_obstacles = 0;
  for (int seed = 1; seed <= 8; ++seed) {
    const ManipulationProblem problem = SyntheticProblem(static_cast<std::uint64_t>(seed));
    const Fabric fabric(Panda(), problem.world, FabricParams{});
    FabricWorkspace ws = fabric.MakeWorkspace();
    std::vector<JointVector> path{problem.start};
    const RolloutResult r =
        fabric.Rollout(problem.start, JointVector::Zero(), problem.goal, &ws, &path);
    // Without the broad phase: the same rollout, bit for bit (the sums keep their order).
    FabricParams every_distance;
    every_distance.broad_phase = false;
    const Fabric reference(Panda(), problem.world, every_distance);
    FabricWorkspace reference_ws = reference.MakeWorkspace();
    const RolloutResult same =
        reference.Rollout(problem.start, JointVector::Zero(), problem.goal, &reference_ws);
    EXPECT_EQ(same.status, r.status);
    EXPECT_EQ(same.steps, r.steps);
    EXPECT_EQ(same.q, r.q);
    EXPECT_EQ(same.qd, r.qd);
    for (std::size_t k = 0; k + 1 < path.size(); k += 5) {
      const JointVector& q = path[k];
      const JointVector qd = (path[k + 1] - q) / fabric.params().dt;
      if (qd.squaredNorm() < 1e-6) continue;
      JointVector qdd;
      ASSERT_TRUE(fabric.Acceleration(q, qd, problem.goal, &ws, &qdd));
      const FullSums full = SumEveryTerm(fabric, q, qd, problem.goal);
      const FabricProbe& probe = ws.probe;
      SCOPED_TRACE(testing::Message() << "seed " << seed << " state " << k);
      EXPECT_LE((probe.metric - full.M).norm(), 1e-12 * full.M.norm());
      EXPECT_LE((probe.energized - full.energized).norm(), 1e-9 * (1 + full.energized.norm()));
      // The clearances: exact within range, at least the range otherwise.
      const double obstacle_range = fabric.params().obstacles.range;
      if (full.min_obstacle_clearance < obstacle_range) {
        EXPECT_EQ(probe.min_obstacle_clearance, full.min_obstacle_clearance);
        ++near_obstacles;
      } else {
        EXPECT_GE(probe.min_obstacle_clearance, obstacle_range);
      }
      if (full.min_self_clearance < fabric.params().self.range)
        EXPECT_EQ(probe.min_self_clearance, full.min_self_clearance);
      else
        EXPECT_GE(probe.min_self_clearance, fabric.params().self.range);
      ++states;
      obstacle_terms += probe.active_obstacle_terms;
      self_terms += probe.active_self_terms;
      queries += probe.obstacle_distances;
      pairs += probe.pair_distances;
    }
  }
  // The comparison covered active terms of both kinds and states near obstacles, and the broad
  // phase did skip work (otherwise it tested nothing).
  EXPECT_GT(states, 100);
  EXPECT_GT(obstacle_terms, 0);
  EXPECT_GT(self_terms, 0);
  EXPECT_GT(near_obstacles, 0);
  EXPECT_LT(queries, states * Panda().num_spheres());
  EXPECT_LT(pairs, states * static_cast<int>(Panda().self_collision_pairs().size()));
  std::printf("%d states: %.1f world queries (of %d spheres), %.1f pair distances (of %zu)\n",
              states, double(queries) / states, Panda().num_spheres(), double(pairs) / states,
              Panda().self_collision_pairs().size());
}

/// Rollouts of the default fabric in generated scenes (tables, shelves) from each problem's start
/// towards its goal and towards random configurations (seeded), without and with the stall test.
struct StallComparison {
  int reached = 0, timeouts = 0, stalled = 0, changed = 0;
  long long steps_without = 0, steps_with = 0;
};

StallComparison CompareStallTest(double window, int problems, int per_problem) {
  FabricParams with;
  with.stall_window = window;
  std::mt19937_64 rng(33);
  StallComparison out;
  for (int seed = 1; seed <= problems; ++seed) {
    const ManipulationProblem problem = SyntheticProblem(static_cast<std::uint64_t>(seed));
    const Fabric plain(Panda(), problem.world, FabricParams{});
    const Fabric stalling(Panda(), problem.world, with);
    FabricWorkspace ws = plain.MakeWorkspace();
    for (int k = 0; k < per_problem; ++k) {
      const JointVector start = problem.start;
      const JointVector goal = k == 0 ? problem.goal : RandomConfiguration(&rng);
      const int trial = seed * 100 + k;
      std::vector<JointVector> full_path, path;
      const RolloutResult a = plain.Rollout(start, JointVector::Zero(), goal, &ws, &full_path);
      const RolloutResult b = stalling.Rollout(start, JointVector::Zero(), goal, &ws, &path);
      out.steps_without += a.steps;
      out.steps_with += b.steps;
      out.reached += a.status == RolloutStatus::kReached;
      out.timeouts += a.status == RolloutStatus::kTimeout;
      out.stalled += b.stalled;
      EXPECT_FALSE(a.stalled);
      // Up to where the stall test ends it, the rollout is the plain one.
      EXPECT_LE(path.size(), full_path.size());
      for (std::size_t i = 0; i < path.size() && i < full_path.size(); ++i)
        EXPECT_EQ(path[i], full_path[i]) << "trial " << trial << ", state " << i;
      if (b.stalled) {
        EXPECT_EQ(b.status, RolloutStatus::kTimeout);
        EXPECT_EQ(b.t, plain.params().t_max);  // charged as the timeout it is taken for
        EXPECT_LT(b.steps, a.steps);
        EXPECT_EQ(b.q, path.back());
        // Inside a caller's time limit below t_max it is pruned instead: the limit comes first.
        const double limit = 0.5 * (b.steps * plain.params().dt + plain.params().t_max);
        const RolloutResult cut =
            stalling.Rollout(start, JointVector::Zero(), goal, &ws, nullptr, limit);
        EXPECT_EQ(cut.status, RolloutStatus::kStopped);
      } else {
        EXPECT_EQ(b.status, a.status);
        EXPECT_EQ(b.steps, a.steps);
      }
      out.changed += b.status != a.status;
    }
  }
  EXPECT_GT(out.reached + out.timeouts, 0);
  return out;
}

TEST(Fabric, TheStallTestEndsOnlyRolloutsThatTimeOut) {
  // 1 s without 0.01 rad of progress: every stalled rollout is one that timed out (held in a
  // local minimum), none that would have reached; the work saved is a large part of the whole.
  const StallComparison c = CompareStallTest(1.0, 8, 6);
  EXPECT_EQ(c.changed, 0);
  EXPECT_GT(c.timeouts, 0) << "no rollout was held in a local minimum: the scene needs changing";
  EXPECT_GT(c.stalled, 0);
  EXPECT_LE(c.stalled, c.timeouts);
  EXPECT_LT(c.steps_with, c.steps_without);
}

TEST(Gfcs, CostIsTheSumOfRolloutTimesPlusThePenaltyOnTimeout) {
  const ManipulationProblem problem = SyntheticProblem(3);
  const Fabric fabric(Panda(), problem.world, FabricParams{});
  FabricWorkspace ws = fabric.MakeWorkspace();
  const GfcsQuery query = QueryOf(problem);
  const JointVector mid = 0.5 * (problem.start + problem.goal);
  const GfcsCandidate c = EvaluateCommandSequence(fabric, query, mid, 100.0, &ws);
  // The same two rollouts by hand.
  const RolloutResult r1 = fabric.Rollout(problem.start, JointVector::Zero(), mid, &ws);
  ASSERT_TRUE(r1.ok());
  const RolloutResult r2 = fabric.Rollout(r1.q, r1.qd, problem.goal, &ws);
  EXPECT_NEAR(c.time, r1.t + r2.t, 1e-12);
  if (r2.ok()) {
    EXPECT_EQ(c.reached, r2.status == RolloutStatus::kReached);
    EXPECT_NEAR(c.cost, r1.t + r2.t + (c.reached ? 0.0 : 100.0), 1e-12);
  }
  // A budget too short to arrive: the penalty applies.
  FabricParams tight;
  tight.t_max = 0.05;
  const Fabric hurried(Panda(), problem.world, tight);
  FabricWorkspace ws2 = hurried.MakeWorkspace();
  const GfcsCandidate late = EvaluateCommandSequence(hurried, query, mid, 100.0, &ws2);
  EXPECT_FALSE(late.reached);
  EXPECT_NEAR(late.cost, late.time + 100.0, 1e-12);
}

TEST(Gfcs, IntermediateCommandsUseTheViaTolerance) {
  const ManipulationProblem problem = SyntheticProblem(3);
  FabricParams loose;
  loose.via_tolerance = 0.4;
  const Fabric fabric(Panda(), problem.world, loose);
  FabricWorkspace ws = fabric.MakeWorkspace();
  const GfcsQuery query = QueryOf(problem);
  const JointVector mid = 0.5 * (problem.start + problem.goal);
  const GfcsCandidate c = EvaluateCommandSequence(fabric, query, mid, 100.0, &ws);
  // By hand: the intermediate rollout hands over within 0.4 rad, the goal's within 0.05 rad.
  const RolloutResult r1 =
      fabric.Rollout(problem.start, JointVector::Zero(), mid, &ws, nullptr,
                     std::numeric_limits<double>::infinity(), CommandRole::kVia);
  ASSERT_EQ(r1.status, RolloutStatus::kReached);
  EXPECT_LT((r1.q - mid).norm(), 0.4);
  EXPECT_GE((r1.q - mid).norm(), 0.05);  // it left while still short of the thesis's epsilon
  EXPECT_GT(r1.qd.norm(), 0.0);          // and still moving
  const RolloutResult r2 = fabric.Rollout(r1.q, r1.qd, problem.goal, &ws);
  EXPECT_NEAR(c.time, r1.t + r2.t, 1e-12);
  if (r2.status == RolloutStatus::kReached) {
    EXPECT_LT((r2.q - problem.goal).norm(), 0.05);
  }
  // The goal role keeps goal_tolerance: from the start, the intermediate command takes longer.
  const RolloutResult strict = fabric.Rollout(problem.start, JointVector::Zero(), mid, &ws);
  EXPECT_GT(strict.t, r1.t);
  FabricParams bad;
  bad.via_tolerance = 0;
  EXPECT_THROW(Fabric(Panda(), problem.world, bad), Error);
}

TEST(Gfcs, SolveIsDeterministicSortedAndBeatsOrMatchesItsFirstBatch) {
  const ManipulationProblem problem = SyntheticProblem(5);
  const Fabric fabric(Panda(), problem.world, FabricParams{});
  const GfcsQuery query = QueryOf(problem);
  GfcsParams params;
  params.batch_size = 8;
  params.batches = 2;
  params.threads = 2;
  params.seed = 4;
  // Which candidates pruning stops depends on the threads' timing (its own tests below); without
  // it every count is deterministic.
  params.prune = false;
  UniformSampler sampler(Panda().limits().lower, Panda().limits().upper);
  const GfcsSolution a = SolveGfcop(fabric, query, &sampler, params);
  const GfcsSolution b = SolveGfcop(fabric, query, &sampler, params);
  ASSERT_NE(a.status, GfcsStatus::kError) << a.message;
  EXPECT_EQ(a.evaluations, 16);
  ASSERT_EQ(a.top.size(), b.top.size());
  for (std::size_t i = 0; i < a.top.size(); ++i) {
    EXPECT_EQ(a.top[i].commands, b.top[i].commands);
    EXPECT_EQ(a.top[i].cost, b.top[i].cost);
    if (i) {
      EXPECT_LE(a.top[i - 1].cost, a.top[i].cost);
    }
  }
  EXPECT_EQ(a.solved(), !a.top.empty() && a.top.front().reached);
  // Every evaluated candidate is counted once, by its last status; with the default penalty (M =
  // 100 s > commands x t_max) a solve is solved iff one candidate reached the goal.
  int counted = 0;
  for (const int n : a.candidate_statuses) counted += n;
  EXPECT_EQ(counted, a.evaluations);
  EXPECT_EQ(a.solved(), a.candidate_statuses[static_cast<int>(RolloutStatus::kReached)] > 0);
  EXPECT_EQ(a.candidate_statuses[static_cast<int>(RolloutStatus::kStopped)], a.pruned);
  EXPECT_EQ(a.candidate_statuses, b.candidate_statuses);
  // The work is counted: at least one step per evaluated candidate, no stall test by default.
  EXPECT_GE(a.integration_steps, a.evaluations);
  EXPECT_EQ(a.integration_steps, b.integration_steps);
  EXPECT_EQ(a.stalled_rollouts, 0);
  // The first batch's sampling is timed inside the solve.
  EXPECT_GE(a.sample_time_s, 0.0);
  EXPECT_LE(a.sample_time_s, a.solve_time_s);
}

TEST(Gfcs, TheFirstBatchIsTheSamplersDrawsAsEvaluated) {
  const ManipulationProblem problem = SyntheticProblem(5);
  const Fabric fabric(Panda(), problem.world, FabricParams{});
  const GfcsQuery query = QueryOf(problem);
  GfcsParams params;
  params.batch_size = 6;
  params.batches = 2;
  params.threads = 2;
  params.seed = 9;
  params.prune = false;
  UniformSampler sampler(Panda().limits().lower, Panda().limits().upper);
  const GfcsSolution s = SolveGfcop(fabric, query, &sampler, params);
  ASSERT_NE(s.status, GfcsStatus::kError) << s.message;
  // The sampler's draws from a generator seeded as the solve's, in draw order, each priced as a
  // lone evaluation prices it.
  std::mt19937_64 rng(static_cast<std::uint64_t>(params.seed));
  Eigen::MatrixXd drawn;
  sampler.Sample(query, params.commands - 1, params.batch_size, &rng, &drawn);
  ASSERT_EQ(s.first_batch.size(), static_cast<std::size_t>(params.batch_size));
  FabricWorkspace ws = fabric.MakeWorkspace();
  int reached = 0;
  for (int c = 0; c < params.batch_size; ++c) {
    const GfcsCandidate& got = s.first_batch[static_cast<std::size_t>(c)];
    EXPECT_EQ(got.commands, drawn.col(c)) << "column " << c;
    const GfcsCandidate alone =
        EvaluateCommandSequence(fabric, query, drawn.col(c), params.penalty, &ws);
    EXPECT_EQ(got.cost, alone.cost) << "column " << c;
    EXPECT_EQ(got.reached, alone.reached) << "column " << c;
    EXPECT_FALSE(got.pruned);
    reached += got.reached;
  }
  // A solve whose first batch reached the goal is solved.
  if (reached > 0) EXPECT_TRUE(s.solved());
}

TEST(Gfcs, APrunedCandidateCostsMoreThanItsBound) {
  const ManipulationProblem problem = SyntheticProblem(3);
  const Fabric fabric(Panda(), problem.world, FabricParams{});
  FabricWorkspace ws = fabric.MakeWorkspace();
  const GfcsQuery query = QueryOf(problem);
  const JointVector mid = 0.5 * (problem.start + problem.goal);
  const GfcsCandidate exact = EvaluateCommandSequence(fabric, query, mid, 100.0, &ws);
  ASSERT_FALSE(exact.pruned);
  ASSERT_GT(exact.time, 0.1);
  for (const double bound : {0.3 * exact.time, 0.9 * exact.time}) {
    const GfcsCandidate c = EvaluateCommandSequence(fabric, query, mid, 100.0, &ws, nullptr, bound);
    EXPECT_TRUE(c.pruned) << bound;
    EXPECT_GT(c.cost, bound);
    EXPECT_LE(c.cost, exact.cost);  // a lower bound of the exact cost
    EXPECT_EQ(c.last_status, RolloutStatus::kStopped);
  }
  const GfcsCandidate loose =
      EvaluateCommandSequence(fabric, query, mid, 100.0, &ws, nullptr, exact.cost + 1.0);
  EXPECT_FALSE(loose.pruned);
  EXPECT_EQ(loose.cost, exact.cost);
  EXPECT_EQ(loose.reached, exact.reached);
}

TEST(Gfcs, PruningKeepsTheTopCandidatesOfAnUnprunedSolve) {
  // Short rollouts keep this quick under the sanitizers; with top_m = 2 some candidates of most
  // problems finish below others' times, so pruning happens.
  FabricParams fabric_params;
  fabric_params.t_max = 3.0;
  std::map<int, int> pruned;  // per number of batches
  for (const std::uint64_t seed : {3u, 5u, 8u}) {
    const ManipulationProblem problem = SyntheticProblem(seed);
    const Fabric fabric(Panda(), problem.world, fabric_params);
    const GfcsQuery query = QueryOf(problem);
    for (const auto& [batches, threads] : {std::pair{1, 2}, std::pair{2, 2}}) {
      GfcsParams params;
      params.batch_size = 8;
      params.batches = batches;
      params.top_m = 2;
      params.threads = threads;
      params.seed = static_cast<std::int64_t>(seed);
      params.prune = false;
      UniformSampler sampler(Panda().limits().lower, Panda().limits().upper);
      const GfcsSolution full = SolveGfcop(fabric, query, &sampler, params);
      params.prune = true;
      const GfcsSolution fast = SolveGfcop(fabric, query, &sampler, params);
      const std::string where = "problem " + std::to_string(seed) + ", " + std::to_string(batches) +
                                " batches, " + std::to_string(threads) + " threads";
      ASSERT_NE(full.status, GfcsStatus::kError) << full.message;
      EXPECT_EQ(full.pruned, 0) << where;
      EXPECT_EQ(fast.status, full.status) << where;
      EXPECT_EQ(fast.evaluations, full.evaluations) << where;
      ASSERT_EQ(fast.top.size(), full.top.size()) << where;
      for (std::size_t i = 0; i < full.top.size(); ++i) {
        EXPECT_EQ(fast.top[i].commands, full.top[i].commands) << where << ", rank " << i;
        EXPECT_EQ(fast.top[i].cost, full.top[i].cost) << where << ", rank " << i;
        EXPECT_EQ(fast.top[i].reached, full.top[i].reached) << where << ", rank " << i;
        EXPECT_FALSE(fast.top[i].pruned) << where << ", rank " << i;
      }
      pruned[batches] += fast.pruned;
    }
  }
  for (const int batches : {1, 2})
    EXPECT_GT(pruned[batches], 0) << "no candidate was pruned with " << batches
                                  << " batches: the test did not test pruning there";
}

/// A uniform sampler that records every batch it draws.
class RecordingSampler : public CommandSampler {
 public:
  RecordingSampler() : uniform_(Panda().limits().lower, Panda().limits().upper) {}
  std::string name() const override { return "recording"; }
  void Sample(const GfcsQuery& query, int intermediate_commands, int count, std::mt19937_64* rng,
              Eigen::MatrixXd* out) override {
    uniform_.Sample(query, intermediate_commands, count, rng, out);
    draws.push_back(*out);
  }
  std::vector<Eigen::MatrixXd> draws;

 private:
  UniformSampler uniform_;
};

TEST(Gfcs, ABatchThatReachedNothingRestartsFromAUniformDraw) {
  const ManipulationProblem problem = SyntheticProblem(5);
  GfcsParams params;
  params.batch_size = 6;
  params.batches = 3;
  params.top_m = 18;  // every evaluated candidate
  params.threads = 1;
  params.prune = false;
  params.seed = 11;
  // 0.05 s per command: no candidate reaches the goal, so every batch reaches nothing.
  FabricParams short_rollouts;
  short_rollouts.t_max = 0.05;
  const Fabric hopeless(Panda(), problem.world, short_rollouts);
  for (const GfcsRestart restart : {GfcsRestart::kNone, GfcsRestart::kUniform}) {
    params.restart = restart;
    RecordingSampler sampler;
    const GfcsSolution s = SolveGfcop(hopeless, QueryOf(problem), &sampler, params);
    ASSERT_EQ(s.status, GfcsStatus::kNotSolved) << s.message;
    EXPECT_EQ(s.evaluations, 18);
    EXPECT_EQ(s.restarts, restart == GfcsRestart::kNone ? 0 : 2);
    ASSERT_EQ(sampler.draws.size(), 1u);  // the solve's sampler draws the first batch only
    // The first batch, and with restarts the two uniform batches drawn after it from the solve's
    // generator, were evaluated as drawn (uniform draws lie inside the box CMA-ES projects onto).
    std::mt19937_64 replay(static_cast<std::uint64_t>(params.seed));
    UniformSampler uniform(Panda().limits().lower, Panda().limits().upper);
    const int drawn = restart == GfcsRestart::kNone ? 1 : 3;
    for (int batch = 0; batch < drawn; ++batch) {
      Eigen::MatrixXd draw;
      uniform.Sample(QueryOf(problem), 1, params.batch_size, &replay, &draw);
      if (batch == 0) {
        EXPECT_EQ(draw, sampler.draws.front());
      }
      for (Eigen::Index c = 0; c < draw.cols(); ++c)
        EXPECT_TRUE(std::any_of(s.top.begin(), s.top.end(),
                                [&](const GfcsCandidate& t) { return t.commands == draw.col(c); }))
            << "restart " << static_cast<int>(restart) << ", batch " << batch << ", column " << c;
    }
  }
  // Batches that reached the goal are told to CMA-ES as in the thesis: the same solve as without
  // restarts.
  const World empty;
  const Fabric fabric(Panda(), empty, FabricParams{});
  GfcsSolution with[2];
  for (const GfcsRestart restart : {GfcsRestart::kNone, GfcsRestart::kUniform}) {
    params.restart = restart;
    RecordingSampler sampler;
    with[static_cast<int>(restart)] = SolveGfcop(fabric, QueryOf(problem), &sampler, params);
  }
  ASSERT_TRUE(with[1].solved());
  EXPECT_EQ(with[1].restarts, 0);
  ASSERT_EQ(with[0].top.size(), with[1].top.size());
  for (std::size_t i = 0; i < with[0].top.size(); ++i) {
    EXPECT_EQ(with[0].top[i].commands, with[1].top[i].commands) << i;
    EXPECT_EQ(with[0].top[i].cost, with[1].top[i].cost) << i;
  }
}

TEST(Gfcs, BadQueriesAreStatusesNotExceptions) {
  const World world;
  const Fabric fabric(Panda(), world, FabricParams{});
  UniformSampler sampler(Panda().limits().lower, Panda().limits().upper);
  GfcsQuery query;
  query.goal[0] = std::nan("");
  const GfcsSolution s = SolveGfcop(fabric, query, &sampler, GfcsParams{});
  EXPECT_EQ(s.status, GfcsStatus::kError);
  EXPECT_NE(s.message.find("non-finite"), std::string::npos);
}

/// Returns columns 1000 k + c (k = its call count) and draws one number per call.
class CountingSampler : public CommandSampler {
 public:
  std::string name() const override { return "counting"; }
  void Sample(const GfcsQuery&, int intermediate_commands, int count, std::mt19937_64* rng,
              Eigen::MatrixXd* out) override {
    (*rng)();
    out->resize(kDof * intermediate_commands, count);
    for (int c = 0; c < count; ++c) out->col(c).setConstant(1000.0 * calls + c);
    ++calls;
  }
  int calls = 0;
};

TEST(SplitSampler, TakesTheRoundedShareFromTheFirstAndTheRestFromTheSecond) {
  CountingSampler a, b;
  SplitSampler split(&a, 0.3, &b);
  EXPECT_EQ(split.name(), "counting+counting");
  std::mt19937_64 rng(4), reference(4);
  Eigen::MatrixXd out;
  split.Sample(GfcsQuery{}, 2, 5, &rng, &out);  // round(1.5) = 2 from a, 3 from b
  ASSERT_EQ(out.rows(), 14);
  ASSERT_EQ(out.cols(), 5);
  const double expected[5] = {0, 1, 0, 1, 2};
  for (int c = 0; c < 5; ++c) EXPECT_EQ(out(0, c), expected[c]) << c;
  EXPECT_EQ(a.calls, 1);
  EXPECT_EQ(b.calls, 1);
  reference();
  reference();  // one draw each, a's first
  EXPECT_TRUE(rng == reference);
  // Shares 0 and 1 call only one of the two.
  SplitSampler none(&a, 0.0, &b), all(&a, 1.0, &b);
  none.Sample(GfcsQuery{}, 1, 3, &rng, &out);
  all.Sample(GfcsQuery{}, 1, 3, &rng, &out);
  EXPECT_EQ(a.calls, 2);
  EXPECT_EQ(b.calls, 2);
  EXPECT_THROW(SplitSampler(&a, 1.5, &b), Error);
  EXPECT_THROW(SplitSampler(nullptr, 0.5, &b), Error);
}

}  // namespace
}  // namespace foresight::manipulation
