// The validity checker against FCL (Debian libfcl 0.7) on random configurations: world
// collisions and clearances of the robot's spheres against boxes and cylinders (synthetic worlds
// with the built-in Panda, MotionBenchMaker worlds with the data Panda), self-collision over the
// checked sphere pairs and the SRDF-disabled ones; then joint limits, non-finite input, motion
// checks and the margin.

#include "inference/manipulation/validity.h"

#include <fcl/fcl.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "inference/manipulation/builtin_panda.h"
#include "inference/manipulation/mbm_problem.h"
#include "inference/manipulation/robot_model.h"
#include "inference/manipulation/synthetic_problems.h"
#include "inference/manipulation/world.h"
#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

using testing::ExpectErrorContains;

/// Configurations whose clearance is this close to zero count as touching: FCL (<=) and the
/// checker (<) may then disagree by design, so they are counted and skipped.
constexpr double kTouching = 1e-9;

/// Declares `dir` = ../shared/data, or skips the test when the shared data is absent.
#define SKIP_WITHOUT_DATA(dir)                                                                   \
  const std::string dir = testing::SharedDataDir();                                              \
  if (dir.empty())                                                                               \
    GTEST_SKIP() << "../shared/data is absent (set FORESIGHT_SOURCE_DIR to the repository root " \
                    "next to shared/): this test needs the data Panda or MotionBenchMaker";

JointVector UniformInLimits(const JointLimits& limits, std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  JointVector q;
  for (int j = 0; j < kDof; ++j)
    q(j) = limits.lower(j) + u01(*rng) * (limits.upper(j) - limits.lower(j));
  return q;
}

std::string Str(const JointVector& q) {
  std::ostringstream out;
  out.precision(17);
  out << "q = [" << q.transpose() << "]";
  return out.str();
}

// ---- FCL mirrors of the world and the robot's spheres -----------------------------------------

using FclObject = std::unique_ptr<fcl::CollisionObjectd>;

/// One FCL object per obstacle, in obstacle order: boxes with full side lengths, cylinders with
/// their full height along local z (FCL's cylinder axis, as ours).
std::vector<FclObject> FclObstacles(const World& world) {
  std::vector<FclObject> out;
  for (const Obstacle& o : world.obstacles()) {
    if (o.is_box()) {
      const Eigen::Vector3d size = 2 * o.box().half_size;
      out.push_back(std::make_unique<fcl::CollisionObjectd>(
          std::make_shared<fcl::Boxd>(size(0), size(1), size(2)), o.box().X_WB));
    } else {
      const Cylinder& c = o.cylinder();
      out.push_back(std::make_unique<fcl::CollisionObjectd>(
          std::make_shared<fcl::Cylinderd>(c.radius, 2 * c.half_height), c.X_WC));
    }
    out.back()->computeAABB();
  }
  return out;
}

/// One FCL sphere per robot sphere, placed by PlaceSpheres.
std::vector<FclObject> FclSpheres(const RobotModel& robot) {
  std::vector<FclObject> out;
  for (const CollisionSphere& s : robot.spheres())
    out.push_back(std::make_unique<fcl::CollisionObjectd>(std::make_shared<fcl::Sphered>(s.radius),
                                                          fcl::Transform3d::Identity()));
  return out;
}

void PlaceSpheres(const KinematicsData& data, std::vector<FclObject>* spheres) {
  for (int s = 0; s < static_cast<int>(spheres->size()); ++s) {
    fcl::Transform3d X = fcl::Transform3d::Identity();
    X.translation() = data.p_WS.col(s);
    (*spheres)[static_cast<size_t>(s)]->setTransform(X);
    (*spheres)[static_cast<size_t>(s)]->computeAABB();
  }
}

bool FclCollide(const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) {
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  return fcl::collide(&a, &b, request, result) > 0;
}

double FclDistance(const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) {
  fcl::DistanceRequestd request;
  fcl::DistanceResultd result;
  return fcl::distance(&a, &b, request, result);
}

// ---- world collisions and clearances against FCL ----------------------------------------------

struct WorldStats {
  int collision = 0, free = 0, touching = 0;  ///< configurations, by the checker's world verdict
  int near_contact = 0;    ///< of those, bisected to within 1e-5 m of contact (0 < |c| < 1e-5)
  long collide_pairs = 0;  ///< sphere/obstacle pairs compared by fcl::collide
  long box_distances = 0, cylinder_distances = 0;  ///< separated pairs compared by fcl::distance
  double box_error = 0, cylinder_error = 0;        ///< max |FCL distance - ours| (m)
  double clearance_error = 0;  ///< max |min FCL distance - MinWorldClearance| on free configs (m)
  /// Sphere/obstacle pairs where FCL and the world disagree (collide or distance), and the first.
  long pair_failures = 0;
  std::string first_pair_failure;
};

std::string Report(const WorldStats& s) {
  std::ostringstream out;
  out << s.collision << " configurations in world collision, " << s.free << " free ("
      << s.near_contact << " of all within 1e-5 m of contact, by bisection), " << s.touching
      << " touching (skipped); " << s.collide_pairs
      << " sphere/obstacle pairs compared by collide; " << s.box_distances
      << " box distances (max |error| " << s.box_error << " m), " << s.cylinder_distances
      << " cylinder distances (max |error| " << s.cylinder_error
      << " m); min clearance max |error| " << s.clearance_error << " m";
  return out.str();
}

/// Counts a failing pair, keeping the first message (millions of pairs would flood the log).
void PairFailure(WorldStats* stats, const std::string& message) {
  if (stats->pair_failures++ == 0) stats->first_pair_failure = message;
}

/// The expectations every world comparison ends with.
void ExpectCovered(const WorldStats& stats) {
  EXPECT_EQ(stats.pair_failures, 0) << "first: " << stats.first_pair_failure;
  EXPECT_GT(stats.collision, 0) << Report(stats);
  EXPECT_GT(stats.free, 0) << Report(stats);
  EXPECT_GT(stats.near_contact, 0) << Report(stats);
  EXPECT_GT(stats.box_distances, 0) << Report(stats);
  EXPECT_GT(stats.cylinder_distances, 0) << Report(stats);
}

/// Compares the checker with FCL on the robot's spheres and the world's obstacles.
class WorldComparison {
 public:
  WorldComparison(const RobotModel& robot, const World& world)
      : robot_(robot),
        world_(world),
        checker_(robot, world, 0.0),
        data_(robot.MakeData()),
        obstacles_(FclObstacles(world)),
        spheres_(FclSpheres(robot)) {}

  /// Compares the verdicts at q (in limits): the checker's world collision (MinWorldClearance < 0,
  /// and Check's kWorldCollision) against fcl::collide over every sphere/obstacle pair, per pair
  /// and overall; and for every pair FCL reports separated, fcl::distance against
  /// World::ObstacleSignedDistance - radius. Returns the checker's min clearance.
  double Compare(const JointVector& q, WorldStats* stats) {
    // FCL 0.7 computes sphere-box and sphere-cylinder distances in closed form
    // (detail::sphereBoxDistance, detail::sphereCylinderDistance; no GJK iterations), so both
    // primitives are held to the same tolerance; the measured differences are ~1e-16 m.
    constexpr double kTol = 1e-9;
    const double clearance = checker_.MinWorldClearance(q, &data_);
    const Validity verdict = checker_.Check(q, &data_);
    const bool collides = clearance < 0;
    // Check looks at the world before self-collisions: its world verdict is exactly this.
    EXPECT_EQ(verdict == Validity::kWorldCollision, collides) << ToString(verdict) << " " << Str(q);
    if (std::abs(clearance) <= kTouching) {
      ++stats->touching;
      return clearance;
    }
    ++(collides ? stats->collision : stats->free);
    PlaceSpheres(data_, &spheres_);
    bool fcl_collides = false;
    double fcl_clearance = std::numeric_limits<double>::infinity();
    for (int s = 0; s < robot_.num_spheres(); ++s) {
      const fcl::CollisionObjectd& sphere = *spheres_[static_cast<size_t>(s)];
      const Eigen::Vector3d centre = data_.p_WS.col(s);
      const double radius = robot_.spheres()[static_cast<size_t>(s)].radius;
      for (int i = 0; i < world_.num_obstacles(); ++i) {
        const fcl::CollisionObjectd& obstacle = *obstacles_[static_cast<size_t>(i)];
        const double ours = world_.ObstacleSignedDistance(i, centre, nullptr) - radius;
        const bool hit = FclCollide(sphere, obstacle);
        fcl_collides |= hit;
        if (std::abs(ours) > kTouching) {
          ++stats->collide_pairs;
          if (hit != (ours < 0)) {
            std::ostringstream m;
            m << "sphere " << s << " vs " << Describe(world_.obstacle(i)) << ": FCL collide " << hit
              << ", our clearance " << ours << ", " << Str(q);
            PairFailure(stats, m.str());
          }
        }
        if (hit) continue;
        const double theirs = FclDistance(sphere, obstacle);
        fcl_clearance = std::min(fcl_clearance, theirs);
        const double error = std::abs(theirs - ours);
        const bool box = world_.obstacle(i).is_box();
        ++(box ? stats->box_distances : stats->cylinder_distances);
        double& worst = box ? stats->box_error : stats->cylinder_error;
        worst = std::max(worst, error);
        if (!(error <= kTol)) {
          std::ostringstream m;
          m.precision(17);
          m << "sphere " << s << " (radius " << radius << ") at " << centre.transpose() << " vs "
            << Describe(world_.obstacle(i)) << ": FCL distance " << theirs << ", ours " << ours;
          PairFailure(stats, m.str());
        }
      }
    }
    EXPECT_EQ(fcl_collides, collides) << "min clearance " << clearance << ", " << Str(q);
    if (!fcl_collides && !collides) {
      stats->clearance_error =
          std::max(stats->clearance_error, std::abs(fcl_clearance - clearance));
      EXPECT_NEAR(fcl_clearance, clearance, kTol) << Str(q);
    }
    return clearance;
  }

  /// `configs` uniform configurations; then, from each of the first `bisections` of them in
  /// collision, bisects the segment to the last free one down to two configurations within
  /// 1e-5 m of contact on either side, and compares those too (the decision boundary).
  void CompareRandom(int configs, int bisections, std::uint64_t seed, WorldStats* stats) {
    constexpr double kNear = 1e-5;
    std::mt19937_64 rng(seed);
    bool have_free = false;
    JointVector last_free = JointVector::Zero();
    for (int k = 0; k < configs; ++k) {
      const JointVector q = UniformInLimits(robot_.limits(), &rng);
      const double c = Compare(q, stats);
      if (c > kTouching) {
        last_free = q;
        have_free = true;
        continue;
      }
      if (c >= -kTouching || !have_free || bisections == 0) continue;
      --bisections;
      JointVector in = q, out = last_free;
      double c_in = c, c_out = checker_.MinWorldClearance(out, &data_);
      for (int i = 0; i < 60 && (c_out >= kNear || c_in <= -kNear); ++i) {
        const JointVector mid = 0.5 * (in + out);
        const double c_mid = checker_.MinWorldClearance(mid, &data_);
        if (c_mid < 0) {
          in = mid;
          c_in = c_mid;
        } else {
          out = mid;
          c_out = c_mid;
        }
      }
      for (const JointVector& near : {in, out})
        stats->near_contact += std::abs(Compare(near, stats)) < kNear;
    }
  }

 private:
  const RobotModel& robot_;
  const World& world_;
  ValidityChecker checker_;
  KinematicsData data_;
  std::vector<FclObject> obstacles_, spheres_;
};

TEST(ValidityVsFcl, FclMirrorMatchesHandComputedDistances) {
  // The mirror's size conventions on hand-computed cases: a box of half sizes (0.1, 0.2, 0.3) at
  // (1, 0, 0), a cylinder of radius 0.2 and half height 0.4 along W's x axis at (0, 1, 0).
  World world;
  Box box;
  box.X_WB.translation() = Eigen::Vector3d(1, 0, 0);
  box.half_size = Eigen::Vector3d(0.1, 0.2, 0.3);
  world.AddBox("box", box);
  Cylinder cylinder;
  cylinder.X_WC =
      Eigen::Translation3d(0, 1, 0) * Eigen::AngleAxisd(EIGEN_PI / 2, Eigen::Vector3d::UnitY());
  cylinder.radius = 0.2;
  cylinder.half_height = 0.4;
  world.AddCylinder("can", cylinder);
  const std::vector<FclObject> obstacles = FclObstacles(world);
  const auto sphere_at = [](const Eigen::Vector3d& p, double r) {
    fcl::Transform3d X = fcl::Transform3d::Identity();
    X.translation() = p;
    return fcl::CollisionObjectd(std::make_shared<fcl::Sphered>(r), X);
  };
  // Box: 0.5 beyond the +z face, 0.5 beyond the +y face, 0.5 beyond the -x face.
  EXPECT_NEAR(FclDistance(sphere_at({1, 0, 0.9}, 0.1), *obstacles[0]), 0.5, 1e-12);
  EXPECT_NEAR(FclDistance(sphere_at({1, 0.8, 0}, 0.1), *obstacles[0]), 0.5, 1e-12);
  EXPECT_NEAR(FclDistance(sphere_at({0.3, 0, 0}, 0.1), *obstacles[0]), 0.5, 1e-12);
  EXPECT_TRUE(FclCollide(sphere_at({1, 0, 0.35}, 0.1), *obstacles[0]));
  EXPECT_FALSE(FclCollide(sphere_at({1, 0, 0.45}, 0.1), *obstacles[0]));
  // Cylinder: 0.5 beyond the +x cap (axis), 0.5 beyond the wall (radially, along z).
  EXPECT_NEAR(FclDistance(sphere_at({1.0, 1, 0}, 0.1), *obstacles[1]), 0.5, 1e-12);
  EXPECT_NEAR(FclDistance(sphere_at({0.3, 1, 0.8}, 0.1), *obstacles[1]), 0.5, 1e-12);
  EXPECT_TRUE(FclCollide(sphere_at({0.45, 1, 0}, 0.1), *obstacles[1]));
  EXPECT_FALSE(FclCollide(sphere_at({0, 1, 0.35}, 0.1), *obstacles[1]));
  EXPECT_NEAR(world.ObstacleSignedDistance(0, {1, 0, 0.9}, nullptr), 0.6, 1e-12);
  EXPECT_NEAR(world.ObstacleSignedDistance(1, {1.0, 1, 0}, nullptr), 0.6, 1e-12);
}

TEST(ValidityVsFcl, SyntheticWorldsWithTheBuiltinPanda) {
  const RobotModel robot = BuiltinPanda();
  WorldStats stats;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SyntheticSceneConfig config;
    config.boxes = 4;
    config.cylinders = 3;
    const World world = MakeSyntheticWorld(config, seed);
    WorldComparison(robot, world).CompareRandom(400, 20, 100 + seed, &stats);
  }
  std::cout << "[ synthetic, built-in Panda ] " << Report(stats) << "\n";
  ExpectCovered(stats);
}

TEST(ValidityVsFcl, MotionBenchMakerWorldsWithTheDataPanda) {
  SKIP_WITHOUT_DATA(data);
  const RobotModel robot = RobotModel::LoadPanda(data + "/franka_panda");
  const std::string problems = data + "/motionbenchmaker_panda/problems";
  WorldStats stats;
  std::uint64_t seed = 7;
  for (const std::string family :
       {"box_panda", "cage_panda", "bookshelf_thin_panda", "table_under_pick_panda"}) {
    for (const ManipulationProblem& p : LoadMbmFamily(problems, family, 1, 3)) {
      WorldComparison comparison(robot, p.world);
      // The problem's start and goal (free, often close to the obstacles), then random ones.
      comparison.Compare(p.start, &stats);
      comparison.Compare(p.goal, &stats);
      comparison.CompareRandom(100, 10, ++seed, &stats);
    }
  }
  std::cout << "[ MotionBenchMaker, data Panda ] " << Report(stats) << "\n";
  ExpectCovered(stats);
}

// ---- self-collision -------------------------------------------------------------------------

/// The robot's spheres as FCL objects, placed at one configuration.
class SpherePairs {
 public:
  explicit SpherePairs(const RobotModel& robot) : robot_(robot), spheres_(FclSpheres(robot)) {}
  void Place(const KinematicsData& data) {
    data_ = &data;
    PlaceSpheres(data, &spheres_);
  }
  /// Whether spheres a and b overlap (or touch) by fcl::collide.
  bool FclOverlap(int a, int b) const {
    return FclCollide(*spheres_[static_cast<size_t>(a)], *spheres_[static_cast<size_t>(b)]);
  }
  /// |c_a - c_b| - r_a - r_b (m).
  double Gap(int a, int b) const {
    return (data_->p_WS.col(a) - data_->p_WS.col(b)).norm() -
           robot_.spheres()[static_cast<size_t>(a)].radius -
           robot_.spheres()[static_cast<size_t>(b)].radius;
  }

 private:
  const RobotModel& robot_;
  std::vector<FclObject> spheres_;
  const KinematicsData* data_ = nullptr;
};

struct SelfStats {
  int self_collision = 0, free = 0, touching = 0;  ///< configurations
  long pairs = 0;                                  ///< sphere pairs compared by fcl::collide
};

/// In an empty world the checker says kSelfCollision exactly when FCL finds an overlapping pair
/// among model.self_collision_pairs(), else kValid.
SelfStats CompareSelfCollisionWithFcl(const RobotModel& robot, int configs, std::uint64_t seed) {
  const World empty;
  const ValidityChecker checker(robot, empty);
  KinematicsData data = robot.MakeData();
  SpherePairs pairs(robot);
  SelfStats stats;
  std::mt19937_64 rng(seed);
  for (int k = 0; k < configs; ++k) {
    const JointVector q = UniformInLimits(robot.limits(), &rng);
    const Validity verdict = checker.Check(q, &data);
    ForwardKinematics(robot, q, &data);
    pairs.Place(data);
    bool fcl_overlap = false;
    double min_gap = std::numeric_limits<double>::infinity();
    for (const auto& [a, b] : robot.self_collision_pairs()) {
      fcl_overlap |= pairs.FclOverlap(a, b);
      min_gap = std::min(min_gap, std::abs(pairs.Gap(a, b)));
      ++stats.pairs;
    }
    if (min_gap <= kTouching) {
      ++stats.touching;
      continue;
    }
    ++(fcl_overlap ? stats.self_collision : stats.free);
    EXPECT_EQ(verdict, fcl_overlap ? Validity::kSelfCollision : Validity::kValid) << Str(q);
  }
  return stats;
}

std::string Report(const SelfStats& s) {
  std::ostringstream out;
  out << s.self_collision << " configurations in self-collision, " << s.free << " free, "
      << s.touching << " touching (skipped); " << s.pairs << " sphere pairs compared";
  return out.str();
}

void ExpectSelfCollisionMatchesFcl(const RobotModel& robot, int configs, std::uint64_t seed,
                                   const std::string& name) {
  const SelfStats stats = CompareSelfCollisionWithFcl(robot, configs, seed);
  std::cout << "[ " << name << " ] " << Report(stats) << "\n";
  EXPECT_GT(stats.self_collision, 0) << Report(stats);
  EXPECT_GT(stats.free, 0) << Report(stats);
}

TEST(SelfCollision, MatchesFclOverTheCheckedPairsBuiltinPanda) {
  ExpectSelfCollisionMatchesFcl(BuiltinPanda(), 3000, 11, "built-in Panda");
}

TEST(SelfCollision, MatchesFclOverTheCheckedPairsDataPanda) {
  SKIP_WITHOUT_DATA(data);
  ExpectSelfCollisionMatchesFcl(RobotModel::LoadPanda(data + "/franka_panda"), 2000, 12,
                                "data Panda");
}

/// Over `first` and `configs` random configurations where no checked pair overlaps (or touches),
/// counts those where some unchecked pair overlaps, by class: rigid (both links on one body),
/// adjacent (bodies joined by one arm joint) or SRDF-only (bodies further apart, disabled by the
/// SRDF); the checker must say kValid there in an empty world. Overlaps are found by centre
/// distance (cheap, so that rare configurations turn up) and confirmed with fcl::collide.
std::array<int, 3> ExpectUncheckedPairsIgnored(const RobotModel& robot, const JointVector& first,
                                               int configs) {
  const World empty;
  const ValidityChecker checker(robot, empty);
  KinematicsData data = robot.MakeData();
  SpherePairs pairs(robot);
  const int n = robot.num_spheres();
  std::vector<char> checked(static_cast<size_t>(n * n), 0);
  for (const auto& [a, b] : robot.self_collision_pairs())
    checked[static_cast<size_t>(a * n + b)] = 1;
  std::array<int, 3> overlapping{0, 0, 0};
  std::mt19937_64 rng(13);
  for (int k = 0; k <= configs; ++k) {
    const JointVector q = k == 0 ? first : UniformInLimits(robot.limits(), &rng);
    ForwardKinematics(robot, q, &data);
    pairs.Place(data);
    bool checked_overlap = false;
    std::array<bool, 3> overlap{false, false, false};
    for (int a = 0; a < n && !checked_overlap; ++a) {
      for (int b = a + 1; b < n; ++b) {
        const double gap = pairs.Gap(a, b);
        if (checked[static_cast<size_t>(a * n + b)]) {
          checked_overlap |= gap <= kTouching;
          continue;
        }
        if (gap > -kTouching) continue;
        EXPECT_TRUE(pairs.FclOverlap(a, b)) << "spheres " << a << ", " << b << " gap " << gap;
        const int la = robot.spheres()[static_cast<size_t>(a)].link;
        const int lb = robot.spheres()[static_cast<size_t>(b)].link;
        const int apart =
            std::abs(robot.num_supporting_joints(la) - robot.num_supporting_joints(lb));
        if (apart > 1) {
          EXPECT_TRUE(robot.CollisionDisabled(la, lb))
              << robot.link_name(la) << ", " << robot.link_name(lb) << " unchecked, not disabled";
        }
        overlap[static_cast<size_t>(std::min(apart, 2))] = true;
      }
    }
    if (checked_overlap) continue;
    for (size_t c = 0; c < 3; ++c) overlapping[c] += overlap[c];
    EXPECT_EQ(checker.Check(q, &data), Validity::kValid) << Str(q);
  }
  return overlapping;
}

/// The SRDF's "ready" pose of the Panda.
JointVector Ready() {
  JointVector q;
  q << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  return q;
}

void ExpectUncheckedPairsNeverReported(const RobotModel& robot, int configs,
                                       const std::string& name) {
  // The ready pose: adjacent links' spheres overlap at their joints, and it is valid.
  const std::array<int, 3> ready = ExpectUncheckedPairsIgnored(robot, Ready(), 0);
  EXPECT_EQ(ready[1], 1) << "no overlapping adjacent pair at the ready pose, or a checked one";
  const std::array<int, 3> n = ExpectUncheckedPairsIgnored(robot, Ready(), configs);
  std::cout << "[ " << name << " ] of " << configs + 1 << " configurations, free of checked "
            << "overlaps with overlapping rigid / adjacent / SRDF-only pairs: " << n[0] << " / "
            << n[1] << " / " << n[2] << "\n";
  EXPECT_GT(n[1], 0);
  EXPECT_GT(n[2], 0);
}

TEST(SelfCollision, UncheckedPairsAreNeverReportedBuiltinPanda) {
  ExpectUncheckedPairsNeverReported(BuiltinPanda(), 1000, "built-in Panda");
}

// SRDF-only overlaps (panda_link2 with panda_link6) without a checked overlap are rare for the
// data Panda: about 1 configuration in 1000.
TEST(SelfCollision, UncheckedPairsAreNeverReportedDataPanda) {
  SKIP_WITHOUT_DATA(data);
  ExpectUncheckedPairsNeverReported(RobotModel::LoadPanda(data + "/franka_panda"), 10000,
                                    "data Panda");
}

// ---- joint limits and non-finite input ------------------------------------------------------

TEST(JointLimits, JustOutsideIsRefusedExactlyOnIsNot) {
  const RobotModel robot = BuiltinPanda();
  const World empty;
  const ValidityChecker checker(robot, empty);
  KinematicsData data = robot.MakeData();
  const JointLimits& limits = robot.limits();
  const JointVector mid = 0.5 * (limits.lower + limits.upper);
  const double inf = std::numeric_limits<double>::infinity();
  for (int j = 0; j < kDof; ++j) {
    for (const double bound : {limits.lower(j), limits.upper(j)}) {
      const double outward = bound == limits.lower(j) ? -inf : inf;
      JointVector q = mid;
      q(j) = bound;
      const Validity on = checker.Check(q, &data);
      EXPECT_NE(on, Validity::kJointLimits) << "joint " << j << " on its limit, " << Str(q);
      EXPECT_NE(on, Validity::kNonFinite) << Str(q);
      q(j) = std::nextafter(bound, outward);
      EXPECT_EQ(checker.Check(q, &data), Validity::kJointLimits) << "joint " << j << ", " << Str(q);
      q(j) = bound + (outward > 0 ? 0.1 : -0.1);
      EXPECT_EQ(checker.Check(q, &data), Validity::kJointLimits) << "joint " << j << ", " << Str(q);
    }
  }
}

TEST(JointLimits, NonFiniteAnglesAreNonFinite) {
  const RobotModel robot = BuiltinPanda();
  const World world = MakeSyntheticWorld(SyntheticSceneConfig{}, 1);
  const ValidityChecker checker(robot, world);
  KinematicsData data = robot.MakeData();
  const JointVector mid = 0.5 * (robot.limits().lower + robot.limits().upper);
  for (int j = 0; j < kDof; ++j) {
    for (const double bad :
         {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity()}) {
      JointVector q = mid;
      q(j) = bad;
      EXPECT_EQ(checker.Check(q, &data), Validity::kNonFinite) << "joint " << j << ", " << Str(q);
      // Also when another joint is out of its limits.
      q((j + 1) % kDof) = robot.limits().upper((j + 1) % kDof) + 1;
      EXPECT_EQ(checker.Check(q, &data), Validity::kNonFinite) << "joint " << j << ", " << Str(q);
    }
  }
}

// ---- motion checks --------------------------------------------------------------------------

/// The built-in Panda in its ready pose sweeping joint 1 from -0.8 to 0.8 rad through a thin
/// plate in front of it.
struct SweepScene {
  SweepScene() : robot(BuiltinPanda()) {
    Box plate;
    plate.X_WB.translation() = Eigen::Vector3d(0.45, 0, 0.45);
    plate.half_size = Eigen::Vector3d(0.1, 0.005, 0.1);
    world.AddBox("plate", plate);
    a = b = Ready();
    a(0) = -0.8;
    b(0) = 0.8;
  }
  RobotModel robot;
  World world;
  JointVector a, b;
};

/// The first invalid state among a + (i / n) (b - a), i = 0..n, as (index, validity); n + 1 and
/// kValid when all are valid.
std::pair<int, Validity> FirstInvalid(const ValidityChecker& checker, const JointVector& a,
                                      const JointVector& b, int n, KinematicsData* data) {
  for (int i = 0; i <= n; ++i) {
    const double s = static_cast<double>(i) / n;
    const Validity v = checker.Check(a + s * (b - a), data);
    if (v != Validity::kValid) return {i, v};
  }
  return {n + 1, Validity::kValid};
}

TEST(CheckMotion, DetectsEveryCollisionLongerThanTheResolution) {
  const SweepScene scene;
  const ValidityChecker checker(scene.robot, scene.world);
  KinematicsData data = scene.robot.MakeData();
  ASSERT_EQ(checker.Check(scene.a, &data), Validity::kValid);
  ASSERT_EQ(checker.Check(scene.b, &data), Validity::kValid);
  // The invalid parts of the segment, densely; the arm crosses the plate with several parts.
  constexpr int kDense = 20000;
  std::vector<std::pair<int, int>> intervals;  // [first, last] invalid dense states
  for (int i = 0; i <= kDense; ++i) {
    const double s = static_cast<double>(i) / kDense;
    if (checker.Check(scene.a + s * (scene.b - scene.a), &data) == Validity::kValid) continue;
    if (intervals.empty() || intervals.back().second != i - 1) intervals.emplace_back(i, i);
    intervals.back().second = i;
  }
  ASSERT_FALSE(intervals.empty());
  const auto [first, last] = intervals.front();
  const double length = (scene.b - scene.a).norm();
  // The first collision lies within (t0, t1) and covers [first, last] / kDense.
  const double t0 = static_cast<double>(first - 1) / kDense;
  const double t1 = static_cast<double>(last + 1) / kDense;
  const double width = (static_cast<double>(last - first) / kDense) * length;  // rad
  ASSERT_GT(width, 0.01);
  for (const double fraction : {0.99, 0.7, 0.5, 0.2, 0.05}) {
    const double resolution = fraction * width;
    double at = -1;
    const Validity v = checker.CheckMotion(scene.a, scene.b, resolution, &data, &at);
    ASSERT_EQ(v, Validity::kWorldCollision)
        << "resolution " << resolution << " rad missed " << width << " rad of collisions";
    // Reported where it is, no later than one resolution step into the interval.
    EXPECT_GE(at, t0);
    EXPECT_LE(at, std::min(t1, t0 + resolution / length + 1.0 / kDense)) << resolution;
    EXPECT_EQ(checker.Check(scene.a + at * (scene.b - scene.a), &data), v);
    // States at i / n, n = ceil(length / resolution) (the most widely spaced that respect it).
    const int n = static_cast<int>(std::ceil(length / resolution));
    const auto [i, expected] = FirstInvalid(checker, scene.a, scene.b, n, &data);
    EXPECT_EQ(v, expected);
    EXPECT_DOUBLE_EQ(at, static_cast<double>(i) / n) << "resolution " << resolution;
  }
  // A resolution longer than the segment checks the ends only, which are valid.
  EXPECT_EQ(checker.CheckMotion(scene.a, scene.b, 2 * length, &data), Validity::kValid);
  EXPECT_EQ(checker.CheckMotion(scene.a, scene.a, 0.01, &data), Validity::kValid);
}

TEST(CheckMotion, SegmentIntoCollisionReportsWhere) {
  const SweepScene scene;
  const ValidityChecker checker(scene.robot, scene.world);
  KinematicsData data = scene.robot.MakeData();
  // b in the plate: the middle of the sweep.
  const JointVector b = 0.5 * (scene.a + scene.b);
  ASSERT_EQ(checker.Check(b, &data), Validity::kWorldCollision);
  for (const double resolution : {0.5, 0.05, 0.01, 10.0}) {
    double at = -1;
    EXPECT_EQ(checker.CheckMotion(scene.a, b, resolution, &data, &at), Validity::kWorldCollision);
    EXPECT_GT(at, 0);
    EXPECT_LE(at, 1);
    EXPECT_EQ(checker.Check(scene.a + at * (b - scene.a), &data), Validity::kWorldCollision);
    if (resolution >= (b - scene.a).norm()) {
      EXPECT_EQ(at, 1.0) << "only the ends are checked";
    }
    // Backwards the first state is invalid.
    EXPECT_EQ(checker.CheckMotion(b, scene.a, resolution, &data, &at), Validity::kWorldCollision);
    EXPECT_EQ(at, 0.0);
  }
  // Other reasons come through as they are.
  JointVector outside = scene.a;
  outside(0) = scene.robot.limits().lower(0) - 0.2;
  double at = -1;
  EXPECT_EQ(checker.CheckMotion(scene.a, outside, 0.05, &data, &at), Validity::kJointLimits);
  EXPECT_GT(at, 0);
  EXPECT_LE(at, 1);
  JointVector nan = scene.a;
  nan(3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(checker.CheckMotion(scene.a, nan, 0.05, &data), Validity::kNonFinite);
}

TEST(CheckMotion, BadResolutionIsAnError) {
  const SweepScene scene;
  const ValidityChecker checker(scene.robot, scene.world);
  KinematicsData data = scene.robot.MakeData();
  const std::vector<std::pair<double, std::string>> bad = {
      {0.0, "got 0"}, {-0.01, "got -0.01"}, {std::numeric_limits<double>::quiet_NaN(), "got nan"}};
  for (const auto& [value, text] : bad) {
    const double resolution = value;  // C++17 lambdas cannot capture structured bindings (Clang)
    ExpectErrorContains([&] { checker.CheckMotion(scene.a, scene.b, resolution, &data); },
                        {"resolution must be positive", text});
  }
}

// ---- margin -----------------------------------------------------------------------------------

TEST(Margin, ValidBelowTheClearanceInCollisionAbove) {
  const RobotModel robot = BuiltinPanda();
  const World world = MakeSyntheticWorld(SyntheticSceneConfig{}, 2);
  const ValidityChecker exact(robot, world);
  KinematicsData data = robot.MakeData();
  std::mt19937_64 rng(21);
  int tested = 0;
  for (int k = 0; k < 2000 && tested < 20; ++k) {
    const JointVector q = UniformInLimits(robot.limits(), &rng);
    if (exact.Check(q, &data) != Validity::kValid) continue;
    const double c = exact.MinWorldClearance(q, &data);
    if (!(c > 0.002 && c < 0.3)) continue;
    ++tested;
    EXPECT_EQ(ValidityChecker(robot, world, 0.999 * c).Check(q, &data), Validity::kValid) << c;
    EXPECT_EQ(ValidityChecker(robot, world, c).Check(q, &data), Validity::kValid) << c;
    EXPECT_EQ(ValidityChecker(robot, world, 1.001 * c).Check(q, &data), Validity::kWorldCollision)
        << c;
    // The margin does not change the clearance itself.
    EXPECT_EQ(ValidityChecker(robot, world, 0.5).MinWorldClearance(q, &data), c);
  }
  EXPECT_EQ(tested, 20);
  // An empty world has no clearance to keep.
  const World empty;
  EXPECT_EQ(ValidityChecker(robot, empty, 10.0).Check(Ready(), &data), Validity::kValid);
}

TEST(Margin, BadMarginIsAnError) {
  const RobotModel robot = BuiltinPanda();
  const World empty;
  for (const double margin :
       {-0.01, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
    ExpectErrorContains([&] { ValidityChecker(robot, empty, margin); }, {"margin"});
}

}  // namespace
}  // namespace foresight::manipulation
