// Basis point set encoding: the lattice, exact surface distances against closed forms and a brute
// force over dense surface samples, coverage checks, the reach box, and the real MBM worlds.

#include "inference/manipulation/bps.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "inference/manipulation/builtin_panda.h"
#include "inference/manipulation/mbm_problem.h"
#include "inference/manipulation/synthetic_problems.h"
#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

namespace fs = std::filesystem;
using testing::ExpectErrorContains;

TEST(BpsLattice, PointsAreLowerPlusSpacingTimesIndexXFastestUpperInclusive) {
  BpsLattice l;
  l.lower = Eigen::Vector3d(0.1, -0.2, 0.3);
  l.upper = Eigen::Vector3d(0.4, 0.25, 0.3);  // 0.3 / 0.15 and 0.45 / 0.15 exactly (up to rounding)
  l.spacing = 0.15;
  EXPECT_EQ(l.counts(), Eigen::Vector3i(3, 4, 1));
  ASSERT_EQ(l.size(), 12);
  const Eigen::Matrix3Xd p = l.points();
  ASSERT_EQ(p.cols(), 12);
  EXPECT_TRUE(p.col(0).isApprox(l.lower));
  EXPECT_TRUE(p.col(1).isApprox(Eigen::Vector3d(0.25, -0.2, 0.3)));
  EXPECT_TRUE(p.col(3).isApprox(Eigen::Vector3d(0.1, -0.05, 0.3)));
  EXPECT_NEAR((p.col(11) - Eigen::Vector3d(0.4, 0.25, 0.3)).norm(), 0, 1e-12);
  l.upper.x() = 0.4 - 1e-6;  // the last x point no longer fits
  EXPECT_EQ(l.counts().x(), 2);
}

TEST(BpsLattice, ValidateNamesTheProblem) {
  BpsLattice l;
  l.upper.y() = l.lower.y() - 0.1;
  ExpectErrorContains([&] { l.Validate("cfg.yaml"); }, {"cfg.yaml", "lower.y", "upper.y"});
  l = BpsLattice();
  l.spacing = 0.001;
  ExpectErrorContains([&] { l.Validate("cfg.yaml"); }, {"cfg.yaml", "10^6"});
  l = BpsLattice();
  l.max_distance = 0;
  ExpectErrorContains([&] { l.Validate("cfg.yaml"); }, {"cfg.yaml", "max_distance"});
}

TEST(BpsLattice, SerializesThroughTheStrictConfigReader) {
  BpsLattice l;
  l.lower = Eigen::Vector3d(-0.5, -1.0, -0.25);
  l.upper = Eigen::Vector3d(1.0, 1.0, 1.25);
  l.spacing = 0.1;
  l.max_distance = 0.5;
  const std::string yaml = config::ToYaml(l);
  const BpsLattice back = config::FromYaml<BpsLattice>(config::ParseYaml(yaml, "t"), "t");
  EXPECT_EQ(back.lower, l.lower);
  EXPECT_EQ(back.upper, l.upper);
  EXPECT_EQ(back.spacing, l.spacing);
  EXPECT_EQ(back.max_distance, l.max_distance);
  ExpectErrorContains(
      [] {
        config::FromYaml<BpsLattice>(config::ParseYaml("lower: {x: 0, w: 1}", "t.yaml"), "t.yaml");
      },
      {"t.yaml", "lower.w"});
  EXPECT_NE(config::ReferenceTable<BpsLattice>().find("`lower.x`"), std::string::npos);
}

TEST(EncodeBps, ClosedFormBoxAndCylinderInsideOutsideAndClipping) {
  World w;
  Box b;
  b.half_size = Eigen::Vector3d(0.1, 0.2, 0.3);
  w.AddBox("box", b);
  Cylinder c;
  c.X_WC.translation() = Eigen::Vector3d(0, 2.0, 0);
  c.radius = 0.1;
  c.half_height = 0.5;
  w.AddCylinder("can", c);
  BpsLattice l;
  l.lower = Eigen::Vector3d(0.05, 0, 0);  // inside the box: 0.05 to the x face
  l.upper = Eigen::Vector3d(0.55, 2.0, 0);
  l.spacing = 0.5;  // points (0.05|0.55, 0|0.5|1.0|1.5|2.0, 0)
  l.max_distance = 0.8;
  ASSERT_EQ(l.size(), 10);
  const Eigen::VectorXf d = EncodeBps(w, l);
  const Eigen::Matrix3Xd p = l.points();
  const auto expected = [&](const Eigen::Vector3d& q) {
    // box: inside -> distance to the nearest face; outside -> Euclidean to the box
    const Eigen::Vector3d h = b.half_size;
    const Eigen::Vector3d a = q.cwiseAbs();
    double box;
    if ((a.array() <= h.array()).all())
      box = (h - a).minCoeff();
    else
      box = (a - h).cwiseMax(0.0).norm();
    // upright cylinder at (0, 2, 0): radial / axial
    const double r = std::hypot(q.x(), q.y() - 2.0), z = std::abs(q.z());
    double can;
    if (r <= 0.1 && z <= 0.5)
      can = std::min(0.1 - r, 0.5 - z);
    else
      can = Eigen::Vector2d(std::max(0.0, r - 0.1), std::max(0.0, z - 0.5)).norm();
    return std::min({box, can, 0.8});
  };
  for (int i = 0; i < l.size(); ++i)
    EXPECT_NEAR(d[i], expected(p.col(i)), 1e-6) << p.col(i).transpose();
  EXPECT_NEAR(d[0], 0.05, 1e-7);  // inside the box
  EXPECT_NEAR(d[8], 0.05, 1e-7);  // (0.05, 2, 0), inside the can: 0.05 to its wall
  EXPECT_NEAR(d[4], 0.8, 1e-7);   // (0.05, 1.0, 0): 0.8 from both, clipped exactly there
  EXPECT_FLOAT_EQ(d[1], 0.45f);   // (0.55, 0, 0): outside the box's x face
  const Eigen::VectorXf empty = EncodeBps(World(), l);
  EXPECT_TRUE((empty.array() == 0.8f).all());
}

TEST(EncodeBps, MatchesBruteForceOverDenseSurfaceSamples) {
  SyntheticSceneConfig scene;
  scene.boxes = 4;
  scene.cylinders = 3;
  for (std::uint64_t seed : {1u, 2u}) {
    const World w = MakeSyntheticWorld(scene, seed);
    BpsLattice l;
    l.lower = w.bounds().min() - Eigen::Vector3d::Constant(0.3);
    l.upper = w.bounds().max() + Eigen::Vector3d::Constant(0.3);
    l.spacing = 0.15;
    l.max_distance = 1.0;
    const double h = 0.02;
    const Eigen::Matrix3Xd s = w.SurfacePoints(h);
    const Eigen::VectorXf d = EncodeBps(w, l);
    const Eigen::Matrix3Xd p = l.points();
    int inside = 0;
    for (int i = 0; i < l.size(); ++i) {
      const double brute =
          std::min(l.max_distance, (s.colwise() - p.col(i)).colwise().norm().minCoeff());
      // every surface point is within h of a sample, and every sample lies on a surface
      EXPECT_LE(d[i], brute + 1e-5) << p.col(i).transpose();
      EXPECT_GE(d[i], brute - h - 1e-5) << p.col(i).transpose();
      if (w.SignedDistance(p.col(i), nullptr) < 0) ++inside;
    }
    EXPECT_EQ(d.size(), l.size());
    EXPECT_GT(inside, 0) << "the lattice should hit some obstacle interiors (seed " << seed << ")";
  }
}

TEST(CheckLatticeCovers, PassesWhenSpannedAndNamesTheAxisOtherwise) {
  BpsLattice l;
  l.lower = Eigen::Vector3d(-1, -1, -1);
  l.upper = Eigen::Vector3d(1, 1, 1);
  l.spacing = 0.5;
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -0.5, 0), Eigen::Vector3d(1, 0.5, 1));
  CheckLatticeCovers(l, box, "here");
  l.upper.y() = 0.4;  // last y point 0.0 < 0.5
  ExpectErrorContains([&] { CheckLatticeCovers(l, box, "cfg.yaml"); }, {"cfg.yaml", "on y", "0.5"});
  l = BpsLattice();
  l.lower = Eigen::Vector3d(-1, -1, 0.2);
  l.upper = Eigen::Vector3d(1, 1, 1);
  l.spacing = 0.2;
  ExpectErrorContains([&] { CheckLatticeCovers(l, box, "cfg.yaml"); }, {"on z", "0.2"});
  l.lower.z() = 0;
  l.upper.x() = 0.9;  // last x point 0.8
  ExpectErrorContains([&] { CheckLatticeCovers(l, box, "w"); }, {"on x", "0.8"});
}

/// Every sphere at random configurations lies inside ReachBox.
void ExpectReachBoxContainsSpheres(const RobotModel& robot) {
  const Eigen::AlignedBox3d box = ReachBox(robot);
  KinematicsData data = robot.MakeData();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u01(0, 1);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (int t = 0; t < 3000; ++t) {
    JointVector q;
    for (int j = 0; j < kDof; ++j)
      q[j] =
          robot.limits().lower[j] + (robot.limits().upper[j] - robot.limits().lower[j]) * u01(rng);
    ForwardKinematics(robot, q, &data);
    for (int s = 0; s < robot.num_spheres(); ++s) {
      const double r = robot.spheres()[s].radius;
      lo = lo.cwiseMin(data.p_WS.col(s) - Eigen::Vector3d::Constant(r));
      hi = hi.cwiseMax(data.p_WS.col(s) + Eigen::Vector3d::Constant(r));
    }
  }
  EXPECT_TRUE((box.min().array() <= lo.array()).all())
      << box.min().transpose() << " vs " << lo.transpose();
  EXPECT_TRUE((box.max().array() >= hi.array()).all())
      << box.max().transpose() << " vs " << hi.transpose();
  // conservative, not absurd: within 0.3 m of the sampled extent
  EXPECT_LT((box.max() - hi).maxCoeff(), 0.3);
  std::cout << "ReachBox " << box.min().transpose() << " .. " << box.max().transpose()
            << "; sampled sphere extent " << lo.transpose() << " .. " << hi.transpose() << "\n";
}

TEST(ReachBox, ContainsEverySphereOfTheBuiltinPanda) {
  ExpectReachBoxContainsSpheres(BuiltinPanda());
}

std::string MbmDir() {
  const std::string data = testing::SharedDataDir();
  if (data.empty()) return "";
  const fs::path dir = fs::path(data) / "motionbenchmaker_panda";
  return fs::is_directory(dir / "compact_json") ? dir.string() : "";
}

TEST(ReachBox, ContainsEverySphereOfTheVampPanda) {
  const std::string data = testing::SharedDataDir();
  if (data.empty() || !fs::exists(fs::path(data) / "franka_panda" / "panda.urdf"))
    GTEST_SKIP() << "../shared/data/franka_panda is absent";
  ExpectReachBoxContainsSpheres(RobotModel::LoadPanda((fs::path(data) / "franka_panda").string()));
}

/// The default lattice on real MotionBenchMaker worlds: it covers the VAMP Panda's reach, and the
/// encodings are sane. Prints the obstacle extents per family (the lattice's design data).
TEST(EncodeBps, DefaultLatticeOnMotionBenchMakerWorlds) {
  const std::string dir = MbmDir();
  if (dir.empty()) GTEST_SKIP() << "../shared/data/motionbenchmaker_panda is absent";
  const BpsLattice lattice;
  EXPECT_EQ(lattice.size(), 4913);
  CheckLatticeCovers(lattice, ReachBox(BuiltinPanda()), "default (built-in Panda)");
  std::cout << "default lattice " << lattice.lower.transpose() << " .. "
            << lattice.upper.transpose() << " spacing " << lattice.spacing << ": N_R "
            << lattice.size() << " (" << lattice.counts().transpose() << ")\n";
  const fs::path panda = fs::path(testing::SharedDataDir()) / "franka_panda";
  if (fs::exists(panda / "panda.urdf"))
    CheckLatticeCovers(lattice, ReachBox(RobotModel::LoadPanda(panda.string())), "default");
  for (const char* family :
       {"table_under_pick_panda", "box_panda", "bookshelf_tall_panda", "cage_panda",
        "bookshelf_thin_panda", "bookshelf_small_panda", "table_pick_panda"}) {
    const auto problems = LoadCompactFamily(dir + "/compact_json/" + family + ".json", 1, 75);
    Eigen::AlignedBox3d all;
    double near = 0, clipped = 0;
    for (const auto& p : problems) {
      all.extend(p.world.bounds());
      const Eigen::VectorXf d = EncodeBps(p.world, lattice);
      ASSERT_TRUE((d.array() >= 0).all() && (d.array() <= 1.0f).all());
      near += (d.array() < 0.15f).cast<double>().mean();
      clipped += (d.array() == 1.0f).cast<double>().mean();
    }
    std::cout << family << ": obstacles within " << all.min().transpose() << " .. "
              << all.max().transpose() << "; lattice points < 0.15 m from a surface "
              << 100 * near / problems.size() << " %, clipped at 1 m "
              << 100 * clipped / problems.size() << " %\n";
  }
}

}  // namespace
}  // namespace foresight::manipulation
