// ORCA (van den Berg et al. 2011): the half-plane of one neighbour against the velocity obstacle
// computed directly (closest approach within the horizon), the 2-D and 3-D programs against grid
// searches, the standard crowds (two agents swapping, a circle swapping to antipodes) in a small
// holonomic simulator, and the unicycle controller built on it.
#include "inference/navigation/orca.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "tests/test_util.h"

namespace foresight::nav {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Smallest distance between A and B over [0, tau] when their relative velocity is `rel`
/// (B's relative position p - rel t): closed form of the closest approach on a segment.
double ClosestApproach(const Eigen::Vector2d& p, const Eigen::Vector2d& rel, double tau) {
  const double r2 = rel.squaredNorm();
  const double t = r2 > 0 ? std::clamp(p.dot(rel) / r2, 0.0, tau) : 0.0;
  return (p - rel * t).norm();
}

/// Holonomic agents all running OrcaVelocity (reciprocal share 0.5), stepped with Euler at dt.
struct Swarm {
  std::vector<Eigen::Vector2d> x, v, goal;
  double radius = 0.5;
  OrcaOptions options;
  double min_gap = kInf;  ///< smallest distance minus the sum of radii over all steps
  int infeasible = 0;

  /// Full speed toward the goal, then exactly onto it. Far from the goal the direction is turned
  /// by 0.01 rad (counter-clockwise for every agent): ORCA deadlocks in perfectly symmetric
  /// encounters (the velocity obstacle's closest boundary point lies straight ahead, so agents only
  /// brake); the paper's and RVO2's crowd experiments perturb the preferred velocity the same way.
  Eigen::Vector2d Preferred(std::size_t i) const {
    const Eigen::Vector2d d = goal[i] - x[i];
    const double n = d.norm();
    if (n <= options.max_speed * options.dt) return d / options.dt;
    const double c = std::cos(0.01), s = std::sin(0.01);
    return Eigen::Vector2d(c * d.x() - s * d.y(), s * d.x() + c * d.y()) * (options.max_speed / n);
  }
  void Step() {
    std::vector<Eigen::Vector2d> next(x.size());
    std::vector<OrcaNeighbour> nbs;
    for (std::size_t i = 0; i < x.size(); ++i) {
      nbs.clear();
      for (std::size_t j = 0; j < x.size(); ++j)
        if (j != i) nbs.push_back({x[j], v[j], radius, 0.5});
      const OrcaResult r = OrcaVelocity(x[i], v[i], radius, Preferred(i), nbs, options);
      infeasible += !r.feasible;
      next[i] = r.velocity;
    }
    v = next;
    for (std::size_t i = 0; i < x.size(); ++i) x[i] += options.dt * v[i];
    for (std::size_t i = 0; i < x.size(); ++i)
      for (std::size_t j = i + 1; j < x.size(); ++j)
        min_gap = std::min(min_gap, (x[i] - x[j]).norm() - 2 * radius);
  }
  bool Arrived(double tol) const {
    for (std::size_t i = 0; i < x.size(); ++i)
      if ((x[i] - goal[i]).norm() > tol) return false;
    return true;
  }
  /// Steps until every agent is within `tol` of its goal; @return the time (inf: not by t_max).
  double Run(double t_max, double tol = 0.05) {
    for (double t = 0; t <= t_max; t += options.dt) {
      if (Arrived(tol)) return t;
      Step();
    }
    return kInf;
  }
};

TEST(Orca, ASingleAgentGetsItsPreferredVelocityClippedToMaxSpeed) {
  OrcaOptions o;
  o.max_speed = 1.0;
  const Eigen::Vector2d x(1, 2), v(0.1, 0);
  EXPECT_TRUE(OrcaVelocity(x, v, 0.4, {3, 4}, {}, o).velocity.isApprox(Eigen::Vector2d(0.6, 0.8)));
  const OrcaResult slow = OrcaVelocity(x, v, 0.4, {0.3, -0.2}, {}, o);
  EXPECT_TRUE(slow.feasible);
  EXPECT_EQ(slow.velocity, Eigen::Vector2d(0.3, -0.2));
  // A neighbour far behind, moving away, does not constrain it either.
  const OrcaResult far = OrcaVelocity(x, v, 0.4, {0.3, -0.2}, {{{-20, 2}, {-1, 0}, 0.4, 0.5}}, o);
  EXPECT_TRUE(far.velocity.isApprox(Eigen::Vector2d(0.3, -0.2), 1e-12));
}

TEST(Orca, TheHalfPlaneTouchesTheVelocityObstacleComputedDirectly) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  OrcaOptions o;
  o.time_horizon = 2.0;
  int checked = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Vector2d a(u(rng), u(rng)), va(u(rng), u(rng));
    OrcaNeighbour b;
    b.position = a + Eigen::Vector2d(3 * u(rng), 3 * u(rng));
    b.velocity = Eigen::Vector2d(u(rng), u(rng));
    b.radius = 0.3;
    b.responsibility = 1.0;  // A takes all: the half-plane is tangent to VO at v_A + u
    const double r = 0.3 + b.radius;
    const Eigen::Vector2d p = b.position - a;
    if (p.norm() <= r + 0.05) continue;  // overlapping pairs: next test
    const OrcaHalfPlane h = OrcaConstraint(a, va, 0.3, b, o);
    EXPECT_NEAR(h.normal.norm(), 1.0, 1e-12);
    // The point lies on the boundary of VO: its closest approach within tau is r.
    EXPECT_NEAR(ClosestApproach(p, h.point - b.velocity, o.time_horizon), r, 1e-9) << trial;
    // Just outside along the normal: no collision within tau; just inside: a collision.
    EXPECT_GT(ClosestApproach(p, h.point + 1e-3 * h.normal - b.velocity, o.time_horizon), r);
    EXPECT_LT(ClosestApproach(p, h.point - 1e-3 * h.normal - b.velocity, o.time_horizon), r);
    // u is the smallest change: no velocity on the other side of VO's boundary is closer to v_A
    // (grid over velocities, membership by the closest approach).
    const bool inside = ClosestApproach(p, va - b.velocity, o.time_horizon) < r;
    const double u_norm = (h.point - va).norm();
    double nearest = kInf;
    const double step = 0.01;
    for (double x = -3; x <= 3; x += step)
      for (double y = -3; y <= 3; y += step) {
        const Eigen::Vector2d w = va + Eigen::Vector2d(x, y);
        if ((ClosestApproach(p, w - b.velocity, o.time_horizon) < r) != inside)
          nearest = std::min(nearest, (w - va).norm());
      }
    if (std::isfinite(nearest)) {
      EXPECT_NEAR(nearest, u_norm, 1.5 * step) << trial;
      ++checked;
    }
    // Every velocity of the half-plane avoids B for tau (B keeps its velocity).
    for (int k = 0; k < 50; ++k) {
      Eigen::Vector2d w = h.point + 3 * Eigen::Vector2d(u(rng), u(rng));
      if (h.Margin(w) < 0) w -= 2 * h.Margin(w) * h.normal;  // mirror into the half-plane
      EXPECT_GE(ClosestApproach(p, w - b.velocity, o.time_horizon), r - 1e-9);
    }
  }
  EXPECT_GE(checked, 20);
}

TEST(Orca, OverlappingAgentsSeparateWithinOneStep) {
  OrcaOptions o;
  o.dt = 0.1;
  const Eigen::Vector2d a(0, 0), va(0, 0);
  const OrcaNeighbour b{{0.5, 0.1}, {0, 0}, 0.4, 1.0};
  const OrcaHalfPlane h = OrcaConstraint(a, va, 0.4, b, o);
  // Velocities of the half-plane reach distance >= r after dt (closest point of D(p/dt, r/dt)).
  const Eigen::Vector2d p = b.position - a;
  EXPECT_NEAR((p - h.point * o.dt).norm(), 0.8, 1e-9);
  EXPECT_LT(h.normal.dot(p), 0) << "the normal points away from the neighbour";
}

/// Grid search over the disc: the feasible velocity closest to `pref` and the least largest
/// violation.
struct GridAnswer {
  double closest = kInf, least_violation = kInf;
};
GridAnswer GridSearch(const std::vector<OrcaHalfPlane>& planes, double max_speed,
                      const Eigen::Vector2d& pref, double step) {
  GridAnswer g;
  for (double x = -max_speed; x <= max_speed; x += step)
    for (double y = -max_speed; y <= max_speed; y += step) {
      const Eigen::Vector2d w(x, y);
      if (w.norm() > max_speed) continue;
      double worst = 0;
      for (const OrcaHalfPlane& h : planes) worst = std::max(worst, -h.Margin(w));
      g.least_violation = std::min(g.least_violation, worst);
      if (worst == 0) g.closest = std::min(g.closest, (w - pref).norm());
    }
  return g;
}

TEST(Orca, TheProgramFindsTheClosestFeasibleVelocityAsAGridSearchDoes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  OrcaOptions o;
  o.max_speed = 1.0;
  int feasible = 0, infeasible = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const Eigen::Vector2d a(0, 0), va(0.6 * u(rng), 0.6 * u(rng)), pref(1.5 * u(rng), 1.5 * u(rng));
    std::vector<OrcaNeighbour> nbs;
    const int n = 2 + trial % 4;
    for (int k = 0; k < n; ++k) {
      Eigen::Vector2d pos;
      do pos = Eigen::Vector2d(3 * u(rng), 3 * u(rng));
      while (pos.norm() < 0.9);
      nbs.push_back({pos, Eigen::Vector2d(u(rng), u(rng)), 0.4, trial % 2 ? 1.0 : 0.5});
    }
    OrcaWorkspace ws;
    const OrcaResult r = OrcaVelocity(a, va, 0.4, pref, nbs, o, &ws);
    ASSERT_EQ(ws.planes.size(), nbs.size());
    ASSERT_TRUE(r.velocity.allFinite());
    EXPECT_LE(r.velocity.norm(), o.max_speed + 1e-9);
    const GridAnswer g = GridSearch(ws.planes, o.max_speed, pref, 0.005);
    if (r.feasible) {
      ++feasible;
      for (const OrcaHalfPlane& h : ws.planes) EXPECT_GE(h.Margin(r.velocity), -1e-7) << trial;
      EXPECT_EQ(r.max_violation, std::max(0.0, r.max_violation));
      // No grid velocity inside every half-plane is closer to the preferred one (within the grid
      // step), and the grid's best comes close to the program's answer.
      EXPECT_GE(g.closest, (r.velocity - pref).norm() - 1e-9) << trial;
      if (std::isfinite(g.closest)) {
        EXPECT_NEAR(g.closest, (r.velocity - pref).norm(), 0.01);
      }
    } else {
      ++infeasible;
      EXPECT_TRUE(std::isinf(g.closest)) << "the grid found a feasible velocity, trial " << trial;
      EXPECT_NEAR(r.max_violation, g.least_violation, 0.01) << trial;
      EXPECT_LE(r.max_violation, g.least_violation + 1e-9) << trial;
    }
  }
  EXPECT_GE(feasible, 20);
}

TEST(Orca, AnInfeasibleCaseReturnsTheLeastViolatingFiniteVelocity) {
  OrcaOptions o;
  o.max_speed = 0.5;
  o.time_horizon = 3;
  // Boxed in by four neighbours closing in fast; the robot takes all the avoidance.
  std::vector<OrcaNeighbour> nbs;
  for (int k = 0; k < 4; ++k) {
    const double angle = 0.3 + k * M_PI / 2;
    const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
    nbs.push_back({1.0 * dir, -1.0 * dir, 0.4, 1.0});
  }
  OrcaWorkspace ws;
  const OrcaResult r = OrcaVelocity({0, 0}, {0, 0}, 0.4, {0.5, 0}, nbs, o, &ws);
  EXPECT_FALSE(r.feasible);
  EXPECT_TRUE(r.velocity.allFinite());
  EXPECT_LE(r.velocity.norm(), o.max_speed + 1e-12);
  const GridAnswer g = GridSearch(ws.planes, o.max_speed, {0.5, 0}, 0.002);
  EXPECT_TRUE(std::isinf(g.closest));
  EXPECT_GT(g.least_violation, 0.0);
  EXPECT_NEAR(r.max_violation, g.least_violation, 0.005);
}

TEST(Orca, TwoAgentsSwapHeadOnWithoutOverlap) {
  for (const double offset : {0.0, 0.05}) {  // exactly head-on, and slightly off
    Swarm s;
    s.x = {{-5, 0}, {5, offset}};
    s.goal = {{5, 0}, {-5, offset}};
    s.v = {{0, 0}, {0, 0}};
    const double t = s.Run(20.0);
    EXPECT_LT(t, 14.0) << "offset " << offset;  // 10 m at 1 m/s plus the detour
    EXPECT_GE(s.min_gap, -1e-6) << "offset " << offset;
  }
}

TEST(Orca, ACircleOfAgentsSwapsToAntipodesWithoutOverlap) {
  // Eight agents on a circle of radius 6 m walk to the antipodes through the centre (12 m at
  // 1 m/s). They meet at the centre and circle around each other before leaving (the vortex of
  // ORCA's crowd experiments); 19.1 s here. Longer horizons (tau = 5 s) or twelve agents with this
  // small bias jam into a packed ring at the centre instead: ORCA has no way out of a symmetric
  // jam, which is why its experiments perturb the preferred velocities.
  Swarm s;
  s.radius = 0.4;
  const int n = 8;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d p(6 * std::cos(2 * M_PI * i / n), 6 * std::sin(2 * M_PI * i / n));
    s.x.push_back(p);
    s.goal.push_back(-p);
    s.v.push_back(Eigen::Vector2d::Zero());
  }
  const double t = s.Run(40.0);
  EXPECT_LT(t, 24.0) << "twice the straight-line time";
  EXPECT_GE(s.min_gap, -1e-6);
}

TEST(OrcaController, DrivesStraightToAFreeGoalAndTurnsTowardOneBehind) {
  OrcaControllerOptions o;
  o.limits = {-1.0, 1.0, 1.0};
  OrcaController c(nullptr, o);
  NavigationInput in;
  in.robot = {0, 0, 0};
  in.goal = {5, 0};
  ControlOutcome u = c.Compute(in);
  ASSERT_TRUE(u.solved());
  EXPECT_NEAR(u.command.v, 1.0, 1e-12);
  EXPECT_NEAR(u.command.omega, 0.0, 1e-12);
  // Goal to the left: turn left at the clamped rate and hardly move (v = |v| cos 90 deg).
  in.goal = {0, 5};
  u = c.Compute(in);
  EXPECT_NEAR(u.command.omega, 1.0, 1e-12);
  EXPECT_NEAR(u.command.v, 0.0, 1e-9);
  // Goal behind with nobody around: turn, never reverse.
  in.goal = {-5, 0.1};
  u = c.Compute(in);
  EXPECT_EQ(u.command.v, 0.0);
  EXPECT_NEAR(std::abs(u.command.omega), 1.0, 1e-12);
  // Bad options name the field.
  o.responsibility = 0;
  testing::ExpectErrorContains([&] { OrcaController bad(nullptr, o); }, {"responsibility"});
}

TEST(OrcaController, PassesAPedestrianWalkingStraightAtIt) {
  // A pedestrian that does not react walks head-on at the unicycle robot; the observations are
  // its last five points 0.1 s apart. The robot takes all the avoidance (responsibility 1).
  OrcaControllerOptions o;
  o.limits = {-1.0, 1.0, 1.0};
  o.responsibility = 1.0;
  OrcaController c(nullptr, o);
  UnicycleState robot{0, 0, 0};
  const Eigen::Vector2d goal(10, 0), ped_velocity(-0.8, 0);
  Eigen::Vector2d ped(8, 0.05);
  Eigen::MatrixXd rows(1, 10);
  double min_gap = kInf;
  bool reached = false;
  for (int k = 0; k < 300 && !reached; ++k) {
    for (int i = 0; i < 5; ++i)
      rows.row(0).segment(2 * i, 2) = (ped - (4 - i) * 0.1 * ped_velocity).transpose();
    NavigationInput in;
    in.robot = robot;
    in.goal = goal;
    in.past_rows = &rows;
    in.observation_step = 0.1;
    const ControlOutcome u = c.Compute(in);
    ASSERT_TRUE(u.solved()) << u.message;
    robot = EulerStep(robot, o.limits.Clamp(u.command), o.dt);
    ped += 0.1 * ped_velocity;
    min_gap = std::min(min_gap, (robot.position() - ped).norm() - 0.8);
    reached = (robot.position() - goal).norm() < 0.5;
  }
  EXPECT_TRUE(reached);
  EXPECT_GT(min_gap, 0.0);
}

}  // namespace
}  // namespace foresight::nav
