// Worlds of boxes and cylinders: signed distances against independent computations (brute-force
// nearest points on densely sampled surfaces, finite differences, hand-computed points), the
// world's minimum, bounds, surface points, validation and the allocation-free query path.

#include "inference/manipulation/world.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "tests/alloc_counter.h"  // replaces operator new: one per binary
#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

using testing::ExpectErrorContains;

Eigen::Isometry3d Pose(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q.normalized().toRotationMatrix();
  X.translation() = t;
  return X;
}

Eigen::Isometry3d RandomPose(std::mt19937_64* rng) {
  std::normal_distribution<double> n01;
  const Eigen::Quaterniond q(n01(*rng), n01(*rng), n01(*rng), n01(*rng));
  return Pose(q, Eigen::Vector3d(n01(*rng), n01(*rng), n01(*rng)) * 0.5);
}

Box RandomBox(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> size(0.05, 0.6);
  return Box{RandomPose(rng), Eigen::Vector3d(size(*rng), size(*rng), size(*rng))};
}

Cylinder RandomCylinder(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> size(0.05, 0.6);
  return Cylinder{RandomPose(rng), size(*rng), size(*rng)};
}

// ---- an independent surface sampler: regular grids that include edges and rims ---------------

/// Points on the box surface, `n` per unit length along each side (edges included), in W.
Eigen::Matrix3Xd SampleBoxSurface(const Box& b, double step) {
  std::vector<Eigen::Vector3d> pts;
  const Eigen::Vector3d& h = b.half_size;
  for (int axis = 0; axis < 3; ++axis) {
    const int i = (axis + 1) % 3, j = (axis + 2) % 3;
    const int ni = static_cast<int>(std::ceil(2 * h(i) / step)),
              nj = static_cast<int>(std::ceil(2 * h(j) / step));
    for (double side : {-1.0, 1.0})
      for (int a = 0; a <= ni; ++a)
        for (int c = 0; c <= nj; ++c) {
          Eigen::Vector3d p;
          p(axis) = side * h(axis);
          p(i) = -h(i) + 2 * h(i) * a / ni;
          p(j) = -h(j) + 2 * h(j) * c / nj;
          pts.push_back(b.X_WB * p);
        }
  }
  Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t k = 0; k < pts.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = pts[k];
  return out;
}

Eigen::Matrix3Xd SampleCylinderSurface(const Cylinder& c, double step) {
  std::vector<Eigen::Vector3d> pts;
  const double r = c.radius, hh = c.half_height;
  const int nt = static_cast<int>(std::ceil(2 * M_PI * r / step)) + 1;
  const int nz = static_cast<int>(std::ceil(2 * hh / step));
  const int nr = static_cast<int>(std::ceil(r / step));
  for (int a = 0; a < nt; ++a) {
    const double t = 2 * M_PI * a / nt;
    for (int k = 0; k <= nz; ++k)
      pts.push_back(c.X_WC *
                    Eigen::Vector3d(r * std::cos(t), r * std::sin(t), -hh + 2 * hh * k / nz));
    for (int k = 0; k <= nr; ++k)
      for (double side : {-1.0, 1.0})
        pts.push_back(c.X_WC * Eigen::Vector3d(r * k / nr * std::cos(t), r * k / nr * std::sin(t),
                                               side * hh));
  }
  Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t k = 0; k < pts.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = pts[k];
  return out;
}

/// Nearest distance from p to a point set, and that point.
double NearestDistance(const Eigen::Matrix3Xd& pts, const Eigen::Vector3d& p,
                       Eigen::Vector3d* nearest = nullptr) {
  Eigen::Index k = 0;
  const double d = std::sqrt((pts.colwise() - p).colwise().squaredNorm().minCoeff(&k));
  if (nearest) *nearest = pts.col(k);
  return d;
}

/// Membership by local coordinates (independent of the distance code).
bool Inside(const Box& b, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p = b.X_WB.inverse() * p_W;
  return (p.cwiseAbs().array() < b.half_size.array()).all();
}
bool Inside(const Cylinder& c, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p = c.X_WC.inverse() * p_W;
  return p.head<2>().norm() < c.radius && std::abs(p.z()) < c.half_height;
}

// ---- hand-computed points ------------------------------------------------------------------

void ExpectSd(const Box& b, const Eigen::Vector3d& p_local, double sd,
              const Eigen::Vector3d& g_local) {
  Eigen::Vector3d g;
  EXPECT_NEAR(SignedDistance(b, b.X_WB * p_local, &g), sd, 1e-12) << p_local.transpose();
  EXPECT_TRUE(testing::MatricesNear(g, b.X_WB.linear() * g_local, 1e-12)) << p_local.transpose();
  EXPECT_NEAR(SignedDistance(b, b.X_WB * p_local, nullptr), sd, 1e-12);
}

void ExpectSd(const Cylinder& c, const Eigen::Vector3d& p_local, double sd,
              const Eigen::Vector3d& g_local) {
  Eigen::Vector3d g;
  EXPECT_NEAR(SignedDistance(c, c.X_WC * p_local, &g), sd, 1e-12) << p_local.transpose();
  EXPECT_TRUE(testing::MatricesNear(g, c.X_WC.linear() * g_local, 1e-12)) << p_local.transpose();
  EXPECT_NEAR(SignedDistance(c, c.X_WC * p_local, nullptr), sd, 1e-12);
}

TEST(BoxSignedDistance, ExactAtKnownPoints) {
  for (const Eigen::Isometry3d& X :
       {Eigen::Isometry3d(Eigen::Isometry3d::Identity()),
        Pose(Eigen::Quaterniond(0.3, -0.2, 0.9, 0.1), Eigen::Vector3d(0.4, -1.0, 2.0))}) {
    const Box b{X, Eigen::Vector3d(1, 2, 3)};
    ExpectSd(b, {2, 0, 0}, 1, {1, 0, 0});  // face centre offsets
    ExpectSd(b, {0, -2.5, 0.3}, 0.5, {0, -1, 0});
    ExpectSd(b, {0.2, 0.1, -5}, 2, {0, 0, -1});
    ExpectSd(b, {2, 3, 4}, std::sqrt(3.0), Eigen::Vector3d(1, 1, 1) / std::sqrt(3.0));  // corner
    ExpectSd(b, {-1.3, 2.4, 0}, 0.5, Eigen::Vector3d(-0.6, 0.8, 0));                    // edge
    ExpectSd(b, {0.5, 0, 0}, -0.5, {1, 0, 0});  // inside, nearest face +x
    ExpectSd(b, {0, 0, -2.9}, -0.1, {0, 0, -1});
    ExpectSd(b, {0, 0, 0}, -1, {1, 0, 0});   // centre: the nearest faces are +-x; + chosen
    ExpectSd(b, {1, 0.5, 0}, 0, {1, 0, 0});  // on a face
  }
  // Ties inside go to the lowest axis; a zero coordinate counts as +.
  const Box cube{Eigen::Isometry3d::Identity(), Eigen::Vector3d(1, 1, 1)};
  ExpectSd(cube, {0.5, 0.5, 0}, -0.5, {1, 0, 0});
  ExpectSd(cube, {-0.5, -0.5, 0}, -0.5, {-1, 0, 0});
  ExpectSd(cube, {0.2, 0.5, -0.5}, -0.5, {0, 1, 0});
  ExpectSd(cube, {1, 1, 0}, 0, {1, 0, 0});  // on an edge
  ExpectSd(cube, {0, 0, 0}, -1, {1, 0, 0});
}

TEST(CylinderSignedDistance, ExactAtKnownPoints) {
  for (const Eigen::Isometry3d& X :
       {Eigen::Isometry3d(Eigen::Isometry3d::Identity()),
        Pose(Eigen::Quaterniond(-0.5, 0.7, 0.1, 0.4), Eigen::Vector3d(-0.3, 0.2, 0.9))}) {
    const Cylinder c{X, 0.5, 1.0};
    ExpectSd(c, {1, 0, 0}, 0.5, {1, 0, 0});  // wall
    ExpectSd(c, {0, -0.8, 0.7}, 0.3, {0, -1, 0});
    ExpectSd(c, {0.6, 0.8, 0}, 0.5, {0.6, 0.8, 0});
    ExpectSd(c, {0, 0, 2}, 1, {0, 0, 1});  // on the axis beyond a cap
    ExpectSd(c, {0.1, 0.2, -1.5}, 0.5, {0, 0, -1});
    ExpectSd(c, {0.8, 0, 1.4}, 0.5, {0.6, 0, 0.8});  // beyond the rim
    ExpectSd(c, {0.3, 0, 0}, -0.2, {1, 0, 0});       // inside, wall nearest
    ExpectSd(c, {0, 0.1, -0.9}, -0.1, {0, 0, -1});   // inside, cap nearest
    ExpectSd(c, {0, 0, 0}, -0.5, {1, 0, 0});         // on the axis: radial = local +x
    ExpectSd(c, {0, 0, 0.7}, -0.3, {0, 0, 1});       // on the axis, cap nearest
    ExpectSd(c, {0, 0.5, 0.2}, 0, {0, 1, 0});        // on the wall
  }
  const Cylinder flat{Eigen::Isometry3d::Identity(), 2.0, 1.0};
  ExpectSd(flat, {0, 0, 0}, -1, {0, 0, 1});  // z = 0 counts as +
  const Cylinder square{Eigen::Isometry3d::Identity(), 1.0, 1.0};
  ExpectSd(square, {0.5, 0, 0.5}, -0.5, {1, 0, 0});  // wall and cap tie: the wall
  ExpectSd(square, {0, 0, 1}, 0, {0, 0, 1});
}

// ---- random shapes against brute force and finite differences -------------------------------

template <typename Shape>
void CheckAgainstBruteForce(const Shape& shape, const Eigen::Matrix3Xd& surface, double step,
                            std::mt19937_64* rng) {
  const Eigen::AlignedBox3d bounds = Bounds(shape);
  std::uniform_real_distribution<double> u(-0.3, 1.3);
  int inside = 0, outside = 0;
  for (int t = 0; t < 300; ++t) {
    const Eigen::Vector3d f(u(*rng), u(*rng), u(*rng));
    const Eigen::Vector3d p = bounds.min() + f.cwiseProduct(bounds.max() - bounds.min()) +
                              Eigen::Vector3d::Constant(0.1) * (f.array() - 0.5).matrix().norm();
    Eigen::Vector3d g, nearest;
    const double sd = SignedDistance(shape, p, &g);
    const double brute = NearestDistance(surface, p, &nearest);
    const bool in = Inside(shape, p);
    (in ? inside : outside)++;
    // Samples lie on the surface, so |sd| <= brute; the grid is `step` fine: brute <= |sd| + step.
    EXPECT_EQ(sd < 0, in) << "sd " << sd << " at " << p.transpose();
    EXPECT_LE(std::abs(sd), brute + 1e-12);
    EXPECT_GE(std::abs(sd), brute - step) << p.transpose();
    EXPECT_NEAR(g.norm(), 1.0, 1e-12);
    if (sd > 0.1) {  // the gradient points from the nearest surface point to p
      EXPECT_GT(g.dot((p - nearest).normalized()), 0.99) << p.transpose();
    }
  }
  EXPECT_GT(inside, 5);
  EXPECT_GT(outside, 50);
}

TEST(BoxSignedDistance, MatchesBruteForceNearestSurfacePoint) {
  std::mt19937_64 rng(1);
  for (int k = 0; k < 8; ++k) {
    const Box b = RandomBox(&rng);
    const double step = 0.004;
    CheckAgainstBruteForce(b, SampleBoxSurface(b, step), step, &rng);
  }
}

TEST(CylinderSignedDistance, MatchesBruteForceNearestSurfacePoint) {
  std::mt19937_64 rng(2);
  for (int k = 0; k < 8; ++k) {
    const Cylinder c = RandomCylinder(&rng);
    const double step = 0.004;
    CheckAgainstBruteForce(c, SampleCylinderSurface(c, step), step, &rng);
  }
}

/// The gradient equals central differences wherever the difference stencil stays on one side of
/// the non-smooth sets (detected by the gradient itself not changing across the stencil).
template <typename Shape>
void CheckGradientByFiniteDifferences(const Shape& shape, std::mt19937_64* rng) {
  const Eigen::AlignedBox3d bounds = Bounds(shape);
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  const double h = 1e-6;
  int checked = 0;
  for (int t = 0; t < 400; ++t) {
    const Eigen::Vector3d f(u(*rng), u(*rng), u(*rng));
    const Eigen::Vector3d p = bounds.min() + f.cwiseProduct(bounds.max() - bounds.min());
    Eigen::Vector3d g;
    SignedDistance(shape, p, &g);
    bool smooth = true;
    for (int i = 0; i < 3; ++i)
      for (double s : {-2 * h, 2 * h}) {
        Eigen::Vector3d gs;
        SignedDistance(shape, p + s * Eigen::Vector3d::Unit(i), &gs);
        smooth = smooth && (gs - g).norm() < 1e-3;
      }
    if (!smooth) continue;
    const Eigen::VectorXd fd = testing::CentralGradient(
        [&](const Eigen::VectorXd& x) {
          return SignedDistance(shape, Eigen::Vector3d(x), nullptr);
        },
        p, h);
    EXPECT_TRUE(testing::MatricesNear(fd, g, 1e-6)) << "at " << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 350);
}

TEST(BoxSignedDistance, GradientMatchesFiniteDifferences) {
  std::mt19937_64 rng(3);
  for (int k = 0; k < 5; ++k) CheckGradientByFiniteDifferences(RandomBox(&rng), &rng);
}

TEST(CylinderSignedDistance, GradientMatchesFiniteDifferences) {
  std::mt19937_64 rng(4);
  for (int k = 0; k < 5; ++k) CheckGradientByFiniteDifferences(RandomCylinder(&rng), &rng);
}

TEST(Bounds, ContainAndTouchTheSurface) {
  std::mt19937_64 rng(5);
  for (int k = 0; k < 5; ++k) {
    const Box b = RandomBox(&rng);
    const Cylinder c = RandomCylinder(&rng);
    for (const auto& [bounds, pts] : {std::make_pair(Bounds(b), SampleBoxSurface(b, 0.005)),
                                      std::make_pair(Bounds(c), SampleCylinderSurface(c, 0.005))}) {
      const Eigen::Vector3d lo = pts.rowwise().minCoeff(), hi = pts.rowwise().maxCoeff();
      EXPECT_TRUE((lo.array() >= bounds.min().array() - 1e-12).all());
      EXPECT_TRUE((hi.array() <= bounds.max().array() + 1e-12).all());
      EXPECT_TRUE(testing::MatricesNear(lo, bounds.min(), 0.005));  // tight
      EXPECT_TRUE(testing::MatricesNear(hi, bounds.max(), 0.005));
    }
  }
}

// ---- World ----------------------------------------------------------------------------------

World RandomWorld(std::mt19937_64* rng, int boxes, int cylinders) {
  World w;
  // Interleaved, so obstacle indices and the two arrays differ.
  for (int k = 0; k < std::max(boxes, cylinders); ++k) {
    if (k < cylinders) w.AddCylinder("cyl" + std::to_string(k), RandomCylinder(rng));
    if (k < boxes) w.AddBox("box" + std::to_string(k), RandomBox(rng));
  }
  return w;
}

TEST(World, EmptyIsInfinitelyFar) {
  const World w;
  Eigen::Vector3d g = Eigen::Vector3d::Constant(7);
  int closest = 3;
  EXPECT_EQ(w.SignedDistance(Eigen::Vector3d(1, 2, 3), &g, &closest),
            std::numeric_limits<double>::infinity());
  EXPECT_EQ(g, Eigen::Vector3d::Zero());
  EXPECT_EQ(closest, -1);
  EXPECT_EQ(w.num_obstacles(), 0);
  EXPECT_TRUE(w.bounds().isEmpty());
  EXPECT_EQ(w.SurfacePoints(0.1).cols(), 0);
}

TEST(World, MinimumOverObstaclesWithItsGradient) {
  std::mt19937_64 rng(6);
  const World w = RandomWorld(&rng, 6, 5);
  ASSERT_EQ(w.num_obstacles(), 11);
  EXPECT_EQ(w.num_boxes(), 6);
  EXPECT_EQ(w.num_cylinders(), 5);
  std::normal_distribution<double> n01;
  for (int t = 0; t < 500; ++t) {
    const Eigen::Vector3d p(n01(rng), n01(rng), n01(rng));
    double best = std::numeric_limits<double>::infinity();
    int best_i = -1;
    Eigen::Vector3d best_g = Eigen::Vector3d::Zero();
    for (int i = 0; i < w.num_obstacles(); ++i) {
      const Obstacle& o = w.obstacle(i);
      Eigen::Vector3d g;
      const double d =
          o.is_box() ? SignedDistance(o.box(), p, &g) : SignedDistance(o.cylinder(), p, &g);
      EXPECT_NEAR(w.ObstacleSignedDistance(i, p, nullptr), d, 1e-12);
      if (d < best) {
        best = d;
        best_i = i;
        best_g = g;
      }
    }
    Eigen::Vector3d g;
    int closest = -2;
    EXPECT_NEAR(w.SignedDistance(p, &g, &closest), best, 1e-12);
    EXPECT_EQ(closest, best_i);
    EXPECT_TRUE(testing::MatricesNear(g, best_g, 1e-12));
    EXPECT_NEAR(w.SignedDistance(p, nullptr), best, 1e-12);
    EXPECT_NEAR(w.SphereClearance(p, 0.05, nullptr), best - 0.05, 1e-12);
  }
}

TEST(World, NonFiniteQueriesGiveNaN) {
  World w;
  w.AddBox("a", Box{});
  Eigen::Vector3d g;
  int closest = 0;
  EXPECT_TRUE(std::isnan(w.SignedDistance(Eigen::Vector3d(std::nan(""), 0, 0), &g, &closest)));
  EXPECT_TRUE(g.array().isNaN().all());
  EXPECT_EQ(closest, -1);
  EXPECT_TRUE(std::isnan(
      w.SignedDistance(Eigen::Vector3d(0, std::numeric_limits<double>::infinity(), 0), nullptr)));
}

TEST(World, TiesGoToTheLowestIndex) {
  World w;
  w.AddCylinder("can", Cylinder{Eigen::Isometry3d::Identity(), 0.5, 1.0});
  w.AddBox("box", Box{Eigen::Isometry3d::Identity(), Eigen::Vector3d(2, 2, 1)});
  int closest = -1;
  EXPECT_EQ(w.SignedDistance(Eigen::Vector3d(0, 0, 5), nullptr, &closest), 4.0);
  EXPECT_EQ(closest, 0);
  // Many equal copies (several SIMD chunks of each type): still the lowest index.
  World many;
  for (int k = 0; k < 9; ++k) {
    many.AddBox("b" + std::to_string(k),
                Box{Eigen::Isometry3d::Identity(), Eigen::Vector3d(2, 2, 1)});
    many.AddCylinder("c" + std::to_string(k), Cylinder{Eigen::Isometry3d::Identity(), 0.5, 1.0});
  }
  EXPECT_EQ(many.SignedDistance(Eigen::Vector3d(0, 0, 5), nullptr, &closest), 4.0);
  EXPECT_EQ(closest, 0);
  World cylinders_first;
  for (int k = 0; k < 9; ++k)
    cylinders_first.AddCylinder("c" + std::to_string(k),
                                Cylinder{Eigen::Isometry3d::Identity(), 0.5, 1.0});
  cylinders_first.AddBox("b", Box{Eigen::Isometry3d::Identity(), Eigen::Vector3d(2, 2, 1)});
  EXPECT_EQ(cylinders_first.SignedDistance(Eigen::Vector3d(0, 0, 5), nullptr, &closest), 4.0);
  EXPECT_EQ(closest, 0);
  EXPECT_EQ(w.FindObstacle("box"), 1);
  EXPECT_EQ(w.FindObstacle("nope"), -1);
}

TEST(World, SphereClearancesMatchSingleQueries) {
  std::mt19937_64 rng(7);
  const World w = RandomWorld(&rng, 4, 4);
  const Eigen::Matrix3Xd centres = Eigen::Matrix3Xd::Random(3, 59);
  const Eigen::VectorXd radii = Eigen::VectorXd::LinSpaced(59, 0.02, 0.1);
  Eigen::VectorXd clearance(59);
  Eigen::Matrix3Xd grad(3, 59);
  w.SphereClearances(centres, radii, clearance, &grad);
  for (int s = 0; s < 59; ++s) {
    Eigen::Vector3d g;
    EXPECT_EQ(clearance(s), w.SphereClearance(centres.col(s), radii(s), &g));
    EXPECT_EQ(grad.col(s), g);
  }
}

TEST(World, DistancesPerObstacleAndAmongAFewAreTheMinimumsNumbers) {
  std::mt19937_64 rng(8);
  const World w = RandomWorld(&rng, 7, 6);  // two SIMD chunks of each type, interleaved
  const int n = w.num_obstacles();
  std::normal_distribution<double> n01;
  std::bernoulli_distribution keep(0.4);
  std::vector<double> distances(static_cast<std::size_t>(n));
  int with_closest = 0, without = 0;
  for (int t = 0; t < 500; ++t) {
    const Eigen::Vector3d p(n01(rng), n01(rng), n01(rng));
    w.ObstacleDistances(p, distances.data());
    for (int i = 0; i < n; ++i)
      EXPECT_NEAR(distances[static_cast<std::size_t>(i)], w.ObstacleSignedDistance(i, p, nullptr),
                  1e-12);
    Eigen::Vector3d g_all, g_some;
    int closest_all = -2, closest_some = -2;
    const double all = w.SignedDistance(p, &g_all, &closest_all);
    // The full list: the same minimum, bit for bit.
    std::vector<int> every(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) every[static_cast<std::size_t>(i)] = i;
    EXPECT_EQ(w.SignedDistanceAmong(p, every.data(), n, &g_some, &closest_some), all);
    EXPECT_EQ(closest_some, closest_all);
    EXPECT_EQ(g_some, g_all);
    // A random subset: the minimum over it (bit for bit the world's when its closest is listed).
    std::vector<int> some;
    for (int i = 0; i < n; ++i)
      if (keep(rng)) some.push_back(i);
    double expected = std::numeric_limits<double>::infinity();
    int expected_closest = -1;
    for (int i : some) {
      if (distances[static_cast<std::size_t>(i)] < expected) {
        expected = distances[static_cast<std::size_t>(i)];
        expected_closest = i;
      }
    }
    const double among = w.SignedDistanceAmong(p, some.data(), static_cast<int>(some.size()),
                                               &g_some, &closest_some);
    EXPECT_EQ(among, expected);
    EXPECT_EQ(closest_some, expected_closest);
    if (std::find(some.begin(), some.end(), closest_all) != some.end()) {
      ++with_closest;
      EXPECT_EQ(among, all);
      EXPECT_EQ(g_some, g_all);
    } else {
      ++without;
      EXPECT_GE(among, all);
    }
  }
  EXPECT_GT(with_closest, 50);
  EXPECT_GT(without, 50);
  // Ties: the lowest listed index, as the minimum.
  World twins;
  twins.AddCylinder("c", Cylinder{Eigen::Isometry3d::Identity(), 0.5, 1.0});
  twins.AddBox("b", Box{Eigen::Isometry3d::Identity(), Eigen::Vector3d(2, 2, 1)});
  const int both[] = {0, 1}, box_only[] = {1};
  int closest = -1;
  EXPECT_EQ(twins.SignedDistanceAmong(Eigen::Vector3d(0, 0, 5), both, 2, nullptr, &closest), 4.0);
  EXPECT_EQ(closest, 0);
  EXPECT_EQ(twins.SignedDistanceAmong(Eigen::Vector3d(0, 0, 5), box_only, 1, nullptr, &closest),
            4.0);
  EXPECT_EQ(closest, 1);
  Eigen::Vector3d g;
  EXPECT_EQ(twins.SignedDistanceAmong(Eigen::Vector3d(0, 0, 5), both, 0, &g, &closest),
            std::numeric_limits<double>::infinity());
  EXPECT_EQ(closest, -1);
  EXPECT_EQ(g, Eigen::Vector3d::Zero());
}

TEST(World, QueriesAllocateNothing) {
  std::mt19937_64 rng(8);
  const World w = RandomWorld(&rng, 12, 9);
  const Eigen::Matrix3Xd centres = Eigen::Matrix3Xd::Random(3, 59);
  const Eigen::VectorXd radii = Eigen::VectorXd::Constant(59, 0.05);
  Eigen::VectorXd clearance(59);
  Eigen::Matrix3Xd grad(3, 59);
  Eigen::Vector3d g;
  int closest = 0;
  double sink = 0;
  std::vector<double> distances(static_cast<std::size_t>(w.num_obstacles()));
  const int listed[] = {1, 4, 7};
  g_allocations = 0;
  g_counting = true;
  for (int s = 0; s < 59; ++s) {
    sink +=
        w.SignedDistance(centres.col(s), &g, &closest) + w.SignedDistance(centres.col(s), nullptr);
    sink += w.ObstacleSignedDistance(closest, centres.col(s), &g);
    sink += w.SignedDistanceAmong(centres.col(s), listed, 3, &g, &closest);
    w.ObstacleDistances(centres.col(s), distances.data());
  }
  w.SphereClearances(centres, radii, clearance, &grad);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(World, BoundsCoverEveryObstacle) {
  std::mt19937_64 rng(9);
  const World w = RandomWorld(&rng, 3, 3);
  Eigen::AlignedBox3d expected;
  for (int i = 0; i < w.num_obstacles(); ++i) expected.extend(w.ObstacleBounds(i));
  EXPECT_TRUE(testing::MatricesNear(w.bounds().min(), expected.min(), 0));
  EXPECT_TRUE(testing::MatricesNear(w.bounds().max(), expected.max(), 0));
}

TEST(World, SurfacePointsLieOnTheSurfaceAndCoverIt) {
  std::mt19937_64 rng(10);
  const World w = RandomWorld(&rng, 3, 3);
  const double spacing = 0.03;
  std::vector<int> owner;
  const Eigen::Matrix3Xd pts = w.SurfacePoints(spacing, &owner);
  ASSERT_EQ(static_cast<Eigen::Index>(owner.size()), pts.cols());
  for (Eigen::Index k = 0; k < pts.cols(); ++k)
    ASSERT_NEAR(w.ObstacleSignedDistance(owner[static_cast<std::size_t>(k)], pts.col(k), nullptr),
                0.0, 1e-12);
  for (int i = 0; i < w.num_obstacles(); ++i) {
    const Obstacle& o = w.obstacle(i);
    const Eigen::Matrix3Xd dense =
        o.is_box() ? SampleBoxSurface(o.box(), 0.01) : SampleCylinderSurface(o.cylinder(), 0.01);
    std::vector<Eigen::Vector3d> mine;
    for (Eigen::Index k = 0; k < pts.cols(); ++k)
      if (owner[static_cast<std::size_t>(k)] == i) mine.push_back(pts.col(k));
    Eigen::Matrix3Xd own(3, static_cast<Eigen::Index>(mine.size()));
    for (std::size_t k = 0; k < mine.size(); ++k) own.col(static_cast<Eigen::Index>(k)) = mine[k];
    double worst = 0;
    for (Eigen::Index k = 0; k < dense.cols(); ++k)
      worst = std::max(worst, NearestDistance(own, dense.col(k)));
    EXPECT_LE(worst, (o.is_box() ? 1.0 / std::sqrt(2.0) : 1.0) * spacing + 1e-12) << Describe(o);
  }
  // Deterministic.
  EXPECT_TRUE(testing::MatricesNear(w.SurfacePoints(spacing), pts, 0));
  ExpectErrorContains([&] { w.SurfacePoints(0.0); }, {"spacing", "positive"});
  ExpectErrorContains([&] { w.SurfacePoints(1e-5); }, {"spacing", "points", "at most"});
}

TEST(World, RejectsBadObstacles) {
  World w;
  w.AddBox("a", Box{});
  ExpectErrorContains([&] { w.AddBox("a", Box{}); }, {"duplicate", "'a'"});
  ExpectErrorContains([&] { w.AddCylinder("", Cylinder{}); }, {"id", "empty"});
  ExpectErrorContains(
      [&] {
        w.AddBox("b", Box{Eigen::Isometry3d::Identity(), Eigen::Vector3d(1, 0, 1)});
      },
      {"box 'b'", "half size", "positive"});
  ExpectErrorContains(
      [&] {
        w.AddCylinder("c", Cylinder{Eigen::Isometry3d::Identity(), -1.0, 1.0});
      },
      {"cylinder 'c'", "radius = -1"});
  ExpectErrorContains(
      [&] {
        w.AddCylinder("c", Cylinder{Eigen::Isometry3d::Identity(), 1.0, std::nan("")});
      },
      {"cylinder 'c'", "half height"});
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 2.0;
  ExpectErrorContains(
      [&] {
        w.AddBox("d", Box{scaled, Eigen::Vector3d::Ones()});
      },
      {"box 'd'", "rotation"});
  Eigen::Isometry3d mirrored = Eigen::Isometry3d::Identity();
  mirrored.linear()(2, 2) = -1.0;
  ExpectErrorContains(
      [&] {
        w.AddBox("e", Box{mirrored, Eigen::Vector3d::Ones()});
      },
      {"box 'e'", "det = -1"});
  Eigen::Isometry3d nan_pose = Eigen::Isometry3d::Identity();
  nan_pose.translation().x() = std::nan("");
  ExpectErrorContains(
      [&] {
        w.AddBox("f", Box{nan_pose, Eigen::Vector3d::Ones()});
      },
      {"box 'f'", "non-finite"});
  EXPECT_EQ(w.num_obstacles(), 1);  // failed additions leave the world unchanged
}

TEST(World, SummaryNamesEveryObstacle) {
  World w;
  w.AddBox("table", Box{Eigen::Isometry3d::Identity(), Eigen::Vector3d(0.5, 0.5, 0.02)});
  w.AddCylinder("can", Cylinder{Eigen::Isometry3d::Identity(), 0.03, 0.07});
  const std::string s = w.Summary();
  EXPECT_NE(s.find("2 obstacles (1 boxes, 1 cylinders)"), std::string::npos) << s;
  EXPECT_NE(s.find("box 'table'"), std::string::npos) << s;
  EXPECT_NE(s.find("cylinder 'can'"), std::string::npos) << s;
}

}  // namespace
}  // namespace foresight::manipulation
