// The imitation metrics against independent computations: the Frechet recursion on a full table
// (memoised, written top-down), closed forms for parallel segments, brute-force signed distances
// to densely sampled obstacle surfaces, and the spacing of resampled polylines.

#include "inference/imitation/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

using foresight::testing::ExpectErrorContains;

constexpr double kPi = 3.14159265358979323846;

Eigen::MatrixXd RandomPath(std::mt19937_64* rng, int d, int n) {
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixXd p(d, n);
  for (int j = 0; j < n; ++j)
    for (int r = 0; r < d; ++r) p(r, j) = g(*rng);
  return p;
}

/// Eiter & Mannila's recursive definition, memoised in a full n x m table, evaluated top-down.
double FrechetRecursive(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::Index n = a.cols(), m = b.cols();
  Eigen::MatrixXd memo = Eigen::MatrixXd::Constant(n, m, -1);
  std::function<double(Eigen::Index, Eigen::Index)> c = [&](Eigen::Index i, Eigen::Index j) {
    if (memo(i, j) >= 0) return memo(i, j);
    const double dij = (a.col(i) - b.col(j)).norm();
    double v;
    if (i == 0 && j == 0)
      v = dij;
    else if (i == 0)
      v = std::max(c(0, j - 1), dij);
    else if (j == 0)
      v = std::max(c(i - 1, 0), dij);
    else
      v = std::max(std::min({c(i - 1, j), c(i - 1, j - 1), c(i, j - 1)}), dij);
    return memo(i, j) = v;
  };
  return c(n - 1, m - 1);
}

TEST(Frechet, MatchesTheRecursiveDefinitionOnRandomPaths) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const int d = 1 + trial % 3;
    const Eigen::MatrixXd a = RandomPath(&rng, d, 1 + static_cast<int>(rng() % 12));
    const Eigen::MatrixXd b = RandomPath(&rng, d, 1 + static_cast<int>(rng() % 12));
    const double f = DiscreteFrechet(a, b);
    EXPECT_DOUBLE_EQ(f, FrechetRecursive(a, b)) << "trial " << trial;
    EXPECT_DOUBLE_EQ(f, DiscreteFrechet(b, a)) << "symmetry, trial " << trial;
    EXPECT_DOUBLE_EQ(f, DiscreteFrechet(a.rowwise().reverse(), b.rowwise().reverse()))
        << "reversing both, trial " << trial;
    // Bounds: at least the end-point distances, at most the largest pairwise distance.
    EXPECT_GE(f, (a.col(0) - b.col(0)).norm());
    EXPECT_GE(f, (a.col(a.cols() - 1) - b.col(b.cols() - 1)).norm());
  }
}

TEST(Frechet, ClosedForms) {
  // Two parallel segments sampled identically, offset by c along the normal: exactly c.
  const int n = 50;
  Eigen::MatrixXd a(2, n), b(2, n);
  const double c = 0.37;
  const Eigen::Vector2d dir(std::cos(0.3), std::sin(0.3)), normal(-dir.y(), dir.x());
  for (int j = 0; j < n; ++j) {
    a.col(j) = dir * (2.0 * j / (n - 1));
    b.col(j) = a.col(j) + c * normal;
  }
  EXPECT_NEAR(DiscreteFrechet(a, b), c, 1e-14);
  EXPECT_EQ(DiscreteFrechet(a, a), 0.0);
  // A single point against a path: the farthest point of the path.
  const Eigen::MatrixXd p = Eigen::Vector2d(0.5, -1.0);
  EXPECT_NEAR(DiscreteFrechet(p, a), (a.colwise() - p.col(0)).colwise().norm().maxCoeff(), 1e-14);
  // Traversing one path backwards costs the distance between its ends (for the monotone coupling).
  EXPECT_NEAR(DiscreteFrechet(a, a.rowwise().reverse()), 2.0, 1e-12);
}

TEST(Frechet, RefusesMismatchedPaths) {
  ExpectErrorContains([] { DiscreteFrechet(Eigen::MatrixXd(2, 3), Eigen::MatrixXd(3, 3)); },
                      {"DiscreteFrechet", "dimension 2 and 3"});
  ExpectErrorContains([] { DiscreteFrechet(Eigen::MatrixXd(2, 0), Eigen::MatrixXd(2, 3)); },
                      {"DiscreteFrechet", "no points"});
}

TEST(ResampleByArcLength, EqualSpacingAndEndpoints) {
  // An L-shaped polyline with a repeated vertex and uneven segments, total length 3 + 4 = 7.
  Eigen::MatrixXd path(2, 6);
  path << 0, 1, 1, 3, 3, 3,  //
      0, 0, 0, 0, 1.5, 4;
  EXPECT_DOUBLE_EQ(ArcLength(path), 7.0);
  for (int count : {2, 3, 8, 57}) {
    const Eigen::MatrixXd r = ResampleByArcLength(path, count);
    ASSERT_EQ(r.rows(), 2);
    ASSERT_EQ(r.cols(), count);
    EXPECT_EQ(r.col(0), path.col(0));
    EXPECT_EQ(r.col(count - 1), path.col(5));
    // Spacing along the path, measured by the closed-form arc-length coordinate of the L.
    for (int k = 0; k < count; ++k) {
      const double s = r(1, k) > 0 ? 3 + r(1, k) : r(0, k);
      EXPECT_NEAR(s, 7.0 * k / (count - 1), 1e-9) << "count " << count << " k " << k;
      EXPECT_TRUE(r(1, k) == 0 || std::abs(r(0, k) - 3) < 1e-12) << "off the polyline";
    }
  }
  // On a fine straight polyline the chord spacing is length / (count - 1).
  Eigen::MatrixXd line(3, 7);
  for (int j = 0; j < 7; ++j) line.col(j) = Eigen::Vector3d(1, 2, 2) * std::pow(j / 6.0, 2);
  const Eigen::MatrixXd r = ResampleByArcLength(line, 11);
  for (int k = 1; k < 11; ++k) EXPECT_NEAR((r.col(k) - r.col(k - 1)).norm(), 0.3, 1e-9);
}

TEST(ResampleByArcLength, ZeroLengthAndBadInput) {
  const Eigen::MatrixXd still = Eigen::Vector2d(1, 2).replicate(1, 4);
  const Eigen::MatrixXd r = ResampleByArcLength(still, 5);
  ASSERT_EQ(r.cols(), 5);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(r.col(k), Eigen::Vector2d(1, 2));
  ExpectErrorContains([&] { ResampleByArcLength(still, 1); }, {"count must be >= 2"});
  ExpectErrorContains([] { ResampleByArcLength(Eigen::MatrixXd(2, 0), 3); }, {"empty path"});
  Eigen::MatrixXd bad = still;
  bad(0, 2) = NAN;
  ExpectErrorContains([&] { ResampleByArcLength(bad, 3); }, {"non-finite"});
}

// ---- obstacles: brute force over densely sampled surfaces -------------------------------------

/// Unsigned distance to a point cloud; sign from the inside test.
double BruteSigned(const Eigen::MatrixXd& surface, const Eigen::VectorXd& p, bool inside) {
  const double d = (surface.colwise() - p).colwise().norm().minCoeff();
  return inside ? -d : d;
}

TEST(Obstacles, DiscSignedDistanceMatchesBruteForce) {
  SphereObstacle disc{Eigen::Vector2d(0.3, -0.2), 0.4};
  const int k = 4000;
  Eigen::MatrixXd surface(2, k);
  for (int i = 0; i < k; ++i)
    surface.col(i) = disc.centre + disc.radius * Eigen::Vector2d(std::cos(2 * kPi * i / k),
                                                                 std::sin(2 * kPi * i / k));
  const double resolution = disc.radius * kPi / k;  // half the spacing of surface samples
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 200; ++t) {
    const Eigen::Vector2d p(u(rng), u(rng));
    const bool inside = (p - disc.centre).norm() <= disc.radius;
    EXPECT_NEAR(disc.SignedDistance(p), BruteSigned(surface, p, inside), resolution)
        << p.transpose();
  }
  // A 3-D ball: its value at the centre and on the axis.
  SphereObstacle ball{Eigen::Vector3d(0, 0, 1), 0.5};
  EXPECT_DOUBLE_EQ(ball.SignedDistance(Eigen::Vector3d(0, 0, 1)), -0.5);
  EXPECT_DOUBLE_EQ(ball.SignedDistance(Eigen::Vector3d(0, 0, 2)), 0.5);
  ExpectErrorContains([&] { ball.SignedDistance(Eigen::Vector2d(0, 0)); },
                      {"SignedDistance", "dimension 2", "dimension 3"});
}

TEST(Obstacles, CylinderSignedDistanceMatchesBruteForce) {
  CylinderObstacle cyl;
  cyl.axis_xy = Eigen::Vector2d(0.5, 0.1);
  cyl.z_min = 0.1, cyl.z_max = 0.4, cyl.radius = 0.075;
  // Surface samples: side wall and both caps, spacing ~2 mm.
  std::vector<Eigen::Vector3d> pts;
  const double h = 0.002;
  const int na = static_cast<int>(2 * kPi * cyl.radius / h);
  for (int a = 0; a < na; ++a) {
    const double th = 2 * kPi * a / na;
    const Eigen::Vector2d dir(std::cos(th), std::sin(th));
    for (double z = cyl.z_min; z <= cyl.z_max + 1e-12; z += h)
      pts.emplace_back(cyl.axis_xy.x() + cyl.radius * dir.x(),
                       cyl.axis_xy.y() + cyl.radius * dir.y(), z);
    for (double r = 0; r < cyl.radius; r += h)
      for (double z : {cyl.z_min, cyl.z_max})
        pts.emplace_back(cyl.axis_xy.x() + r * dir.x(), cyl.axis_xy.y() + r * dir.y(), z);
  }
  Eigen::MatrixXd surface(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i) surface.col(static_cast<Eigen::Index>(i)) = pts[i];
  const double resolution = 2.5 * h;  // covers the sampling gaps on walls and caps
  auto inside = [&](const Eigen::Vector3d& p) {
    return (p.head<2>() - cyl.axis_xy).norm() <= cyl.radius && p.z() >= cyl.z_min &&
           p.z() <= cyl.z_max;
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  int above = 0, below = 0, rim = 0, in = 0;
  for (int t = 0; t < 300; ++t) {
    Eigen::Vector3d p;
    switch (t % 4) {
      case 0:  // anywhere around
        p = Eigen::Vector3d(0.5 + 0.25 * u(rng), 0.1 + 0.25 * u(rng), 0.25 + 0.3 * u(rng));
        break;
      case 1:  // above or below a cap, within the radius
        p = Eigen::Vector3d(
            0.5 + 0.05 * u(rng), 0.1 + 0.05 * u(rng),
            u(rng) > 0 ? 0.4 + 0.1 * std::abs(u(rng)) : 0.1 - 0.1 * std::abs(u(rng)));
        break;
      case 2: {  // near the rim (inside or out)
        const double th = kPi * u(rng);
        const double r = cyl.radius + 0.02 * u(rng);
        p = Eigen::Vector3d(0.5 + r * std::cos(th), 0.1 + r * std::sin(th),
                            (u(rng) > 0 ? 0.4 : 0.1) + 0.02 * u(rng));
        break;
      }
      default:  // inside
        p = Eigen::Vector3d(0.5 + 0.05 * u(rng), 0.1 + 0.05 * u(rng), 0.25 + 0.14 * u(rng));
    }
    const bool is_inside = inside(p);
    in += is_inside;
    above += p.z() > cyl.z_max;
    below += p.z() < cyl.z_min;
    rim += std::abs((p.head<2>() - cyl.axis_xy).norm() - cyl.radius) < 0.02 &&
           (std::abs(p.z() - cyl.z_max) < 0.02 || std::abs(p.z() - cyl.z_min) < 0.02);
    EXPECT_NEAR(cyl.SignedDistance(p), BruteSigned(surface, p, is_inside), resolution)
        << p.transpose();
  }
  EXPECT_GT(in, 50);
  EXPECT_GT(above, 30);
  EXPECT_GT(below, 30);
  EXPECT_GT(rim, 50);
}

TEST(Obstacles, MaxCollisionDepth) {
  SphereObstacle disc{Eigen::Vector2d(0, 0), 1.0};
  // A straight line at height y = 0.8 crossing the disc: deepest point at (0, 0.8), sd = -0.2.
  Eigen::MatrixXd line(2, 201);
  for (int j = 0; j < 201; ++j) line.col(j) = Eigen::Vector2d(-2 + 0.02 * j, 0.8);
  EXPECT_NEAR(MaxCollisionDepth(line, disc, 0.0), 0.2, 1e-12);
  EXPECT_NEAR(MaxCollisionDepth(line, disc, 0.05), 0.25, 1e-12);
  // Clear of the disc by 0.5: no collision for a point, and for a ball of radius 0.49.
  line.row(1).setConstant(1.5);
  EXPECT_EQ(MaxCollisionDepth(line, disc, 0.0), 0.0);
  EXPECT_EQ(MaxCollisionDepth(line, disc, 0.49), 0.0);
  EXPECT_NEAR(MaxCollisionDepth(line, disc, 0.6), 0.1, 1e-12);

  CylinderObstacle cyl{Eigen::Vector2d(0.5, 0.0), 0.0, 0.3, 0.075};
  // A horizontal pass at z = 0.2 through the axis: depth = radius; a pass over the cap at z = 0.35.
  Eigen::MatrixXd pass(3, 101);
  for (int j = 0; j < 101; ++j) pass.col(j) = Eigen::Vector3d(0.5, -0.5 + 0.01 * j, 0.2);
  EXPECT_NEAR(MaxCollisionDepth(pass, cyl, 0.0), 0.075, 1e-12);
  pass.row(2).setConstant(0.35);
  EXPECT_EQ(MaxCollisionDepth(pass, cyl, 0.0), 0.0);
  EXPECT_NEAR(MaxCollisionDepth(pass, cyl, 0.06), 0.01, 1e-12);

  ExpectErrorContains([&] { MaxCollisionDepth(line, cyl, 0.0); },
                      {"MaxCollisionDepth (cylinder)", "dimension 2", "expected 3"});
  ExpectErrorContains([&] { MaxCollisionDepth(line, disc, -0.1); }, {"body_radius", "-0.1"});
  ExpectErrorContains([&] { MaxCollisionDepth(pass, disc, 0.0); }, {"dimension 3"});
  Eigen::MatrixXd bad = line;
  bad(1, 7) = NAN;
  ExpectErrorContains([&] { MaxCollisionDepth(bad, disc, 0.0); }, {"non-finite"});
}

TEST(Metrics, DistanceToNearestAndReachedGoal) {
  // Two reference segments on y = 0 and y = 1 (dense), path points in between: min(|y|, |1 - y|).
  Eigen::MatrixXd r0(2, 1001), r1(2, 1001);
  for (int j = 0; j < 1001; ++j) {
    r0(0, j) = r1(0, j) = 0.001 * j;  // element-wise: GCC 12 misreads a Vector2d column store
    r0(1, j) = 0;
    r1(1, j) = 1;
  }
  Eigen::MatrixXd path(2, 4);
  path << 0.1, 0.3, 0.5, 0.9,  //
      0.2, 0.45, 0.9, -0.3;
  const Eigen::VectorXd d = DistanceToNearest(path, {r0, r1});
  const Eigen::Vector4d expected(0.2, 0.45, 0.1, 0.3);
  EXPECT_TRUE(foresight::testing::MatricesNear(d, expected, 1e-12));
  ExpectErrorContains([&] { DistanceToNearest(path, {Eigen::MatrixXd(3, 2)}); },
                      {"reference 0", "dimension 3"});
  ExpectErrorContains([&] { DistanceToNearest(path, {}); }, {"no reference points"});

  EXPECT_TRUE(ReachedGoal(path, Eigen::Vector2d(0.9, -0.25), 0.05 + 1e-12));
  EXPECT_FALSE(ReachedGoal(path, Eigen::Vector2d(0.9, -0.25), 0.04));
  path(0, 3) = NAN;
  EXPECT_FALSE(ReachedGoal(path, Eigen::Vector2d(0.9, -0.3), 1e9));
  ExpectErrorContains([&] { ReachedGoal(path, Eigen::Vector3d::Zero(), 1); }, {"dimension"});
}

}  // namespace
}  // namespace foresight::imitation
