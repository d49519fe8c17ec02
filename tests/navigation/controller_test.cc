// SPAN controller, reactive baseline and CL-RRT*: costs against brute force, closed-loop behaviour
// in small scenes, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "inference/mapping/grid_map.h"
#include "inference/navigation/cl_rrt_star.h"
#include "inference/navigation/goal_distance.h"
#include "inference/navigation/span_controller.h"
#include "inference/navigation/static_clearance.h"
#include "tests/test_util.h"

namespace foresight::nav {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// 12 m x 8 m free room with 0.1 m cells; `wall` adds a vertical wall at x = 5 with a gap at y in
/// [5, 6.5].
occupancy::GridMap Room(bool wall) {
  occupancy::GridGeometry g;
  g.x_min = -1;
  g.y_min = -1;
  g.resolution = 0.1;
  g.nx = 140;
  g.ny = 100;
  Eigen::MatrixXf p = Eigen::MatrixXf::Constant(g.ny, g.nx, 0.05f);
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix) {
      const double x = g.x_min + (ix + 0.5) * g.resolution, y = g.y_min + (iy + 0.5) * g.resolution;
      const bool border = x < -0.5 || x > 12.5 || y < -0.5 || y > 8.5;
      const bool w = wall && std::abs(x - 5.0) < 0.15 && !(y > 5.0 && y < 6.5);
      if (border || w) p(iy, ix) = 0.95f;
    }
  return occupancy::GridMap(g, p, occupancy::CellType::kFloat32);
}

/// Rows of standing pedestrians observed for `p` steps.
Eigen::MatrixXd Standing(const std::vector<Eigen::Vector2d>& at, int p) {
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(at.size()), 2 * p);
  for (std::size_t n = 0; n < at.size(); ++n)
    for (int i = 0; i < p; ++i)
      rows.row(static_cast<Eigen::Index>(n)).segment(2 * i, 2) = at[n].transpose();
  return rows;
}

TEST(StaticCollisionField, TabulatesTheSweptOccupancy) {
  const occupancy::GridMap map = Room(true);
  const StaticCollisionField field(map, 0.4, 0.05);
  occupancy::MapWorkspace ws = field.MakeWorkspace();
  int disagree = 0, checked = 0;
  for (double x = 0.0; x < 12.0; x += 0.173)
    for (double y = 0.0; y < 8.0; y += 0.191) {
      const double exact = SweptOccupancy(map, &ws, x, y, 0.4, 64);
      const double tab = field.Value(x, y, &ws);
      // Conservative up to the raster step: near the boundary the tabulated value may be larger.
      if ((exact > 0.25) != (tab > 0.25)) {
        ++disagree;
        EXPECT_GT(tab, 0.25) << "the table missed an obstacle at " << x << ", " << y;
      }
      ++checked;
    }
  EXPECT_LT(disagree, checked / 20);
  EXPECT_TRUE(field.Collides(5.0, 2.0, 0.25, &ws));    // on the wall
  EXPECT_TRUE(field.Collides(4.7, 2.0, 0.25, &ws));    // robot disc touches the wall
  EXPECT_FALSE(field.Collides(4.2, 2.0, 0.25, &ws));   // clear of it
  EXPECT_FALSE(field.Collides(5.0, 5.75, 0.25, &ws));  // in the gap
  EXPECT_TRUE(field.Collides(-3.0, 2.0, 0.25, &ws));   // outside the map: prior 0.5
}

TEST(GoalDistanceField, IsEuclideanInOpenSpaceAndGoesAroundWalls) {
  const occupancy::GridMap open = Room(false), walled = Room(true);
  const StaticCollisionField open_field(open, 0.4, 0.05), walled_field(walled, 0.4, 0.05);
  const Eigen::Vector2d goal(9, 2);
  const GoalDistanceField free_space(open_field, goal, 0.25), around(walled_field, goal, 0.25);
  // Away from walls: the straight-line distance up to the 8-connected grid error (<= 8 %).
  for (const Eigen::Vector2d& x :
       {Eigen::Vector2d(3, 2), Eigen::Vector2d(5, 4), Eigen::Vector2d(7, 3.5)}) {
    const double euclid = (x - goal).norm();
    EXPECT_GE(free_space.Distance(x), euclid - 0.05);
    EXPECT_LE(free_space.Distance(x), 1.09 * euclid + 0.05);
  }
  // Behind the wall (x = 5, gap at y in [5, 6.5]): the way leads through the gap.
  const Eigen::Vector2d x(3, 2), gap(5, 5.75);
  const double via_gap = (x - gap).norm() + (gap - goal).norm();
  EXPECT_GT(around.Distance(x), via_gap - 0.1);
  EXPECT_LT(around.Distance(x), 1.09 * via_gap + 1.5);  // grid error plus the wall-margin cost
  EXPECT_GT(around.Distance(x), 1.3 * (x - goal).norm());
  // Inside the wall there is no free path: the Euclidean distance plus the penalty.
  EXPECT_GT(around.Distance(Eigen::Vector2d(5.0, 2.0)), around.unreachable_penalty);
}

SpanControllerOptions Options() {
  SpanControllerOptions o;
  o.initialisations = 12;
  return o;
}

TEST(SpanController, FreeSpaceDrivesStraightAtTheGoal) {
  SpanController c(nullptr, nullptr, Options());
  NavigationInput in;
  in.robot = {0, 0, 0};
  in.goal = {10, 0};
  const ControlOutcome out = c.Compute(in);
  EXPECT_TRUE(out.solved());
  EXPECT_NEAR(out.command.v, 1.0, 1e-3);
  EXPECT_NEAR(out.command.omega, 0.0, 2e-2);
  EXPECT_EQ(out.tau, kInf);
  EXPECT_NEAR(out.cost, 6.0, 1e-2);
}

TEST(SpanController, CostIsDistancePlusKappaOverTheFirstCollisionTime) {
  SpanController c(nullptr, nullptr, Options());
  const Eigen::MatrixXd rows = Standing({{2.0, 0.0}}, 5);
  NavigationInput in;
  in.robot = {0, 0, 0};
  in.goal = {10, 0};
  in.past_rows = &rows;
  c.Forecast(in);
  double tau = 0;
  const double cost = c.Cost(in.robot, in.goal, {1.0, 0.0}, &tau);
  // Straight at 1 m/s: first step with ||x - o|| < 0.8 is x = 1.3 m (step 13; x = 1.2 is exactly
  // 0.8 away).
  EXPECT_NEAR(tau, 1.3, 1e-9);
  EXPECT_NEAR(cost, 6.0 + 100.0 / 1.3, 1e-9);
  EXPECT_NEAR(c.Cost(in.robot, in.goal, {0.0, 0.0}, &tau), 10.0, 1e-12);
  EXPECT_EQ(tau, kInf);
}

// Piecewise-constant controls (segments): the same control in every segment is the one-control
// cost; a stop for the first half then full speed ends 2 m from the start (closed form), and the
// controller with two segments drives straight at a goal in free space.
TEST(SpanController, SegmentedControlsFollowTheirClosedForm) {
  SpanController c(nullptr, nullptr, Options());
  const UnicycleState robot{0, 0, 0};
  const Eigen::Vector2d goal(10, 0);
  double tau_one = 0, tau_two = 0;
  EXPECT_EQ(c.Cost(robot, goal, Control{0.7, 0.2}, &tau_one),
            c.Cost(robot, goal, std::vector<Control>{{0.7, 0.2}, {0.7, 0.2}}, &tau_two));
  EXPECT_EQ(tau_one, tau_two);
  // Steps 1-20 (t < 2 s) stopped, steps 21-40 at 1 m/s: x(T) = 2 m, 8 m from the goal.
  EXPECT_NEAR(c.Cost(robot, goal, std::vector<Control>{{0.0, 0.0}, {1.0, 0.0}}, nullptr), 8.0,
              1e-9);
  SpanControllerOptions o = Options();
  o.segments = 2;
  SpanController two(nullptr, nullptr, o);
  NavigationInput in;
  in.robot = robot;
  in.goal = goal;
  const ControlOutcome out = two.Compute(in);
  EXPECT_TRUE(out.solved());
  EXPECT_NEAR(out.command.v, 1.0, 1e-3);
  EXPECT_NEAR(out.cost, 6.0, 1e-2);
  o.segments = 0;
  EXPECT_NE(o.Problems().find("segments = 0"), std::string::npos);
  EXPECT_THROW(c.Cost(robot, goal, std::vector<Control>{}, nullptr), Error);
}

TEST(SpanController, CobylaFindsAsGoodAControlAsAGridSearch) {
  const occupancy::GridMap map = Room(false);
  const StaticCollisionField field(map, 0.4, 0.05);
  SpanController c(nullptr, &field, Options());
  const Eigen::MatrixXd rows = Standing({{2.5, 0.3}, {3.0, -1.2}, {4.0, 2.0}}, 5);
  NavigationInput in;
  in.robot = {0.5, 1.0, 0.2};
  in.goal = {10, 1};
  in.past_rows = &rows;
  const ControlOutcome out = c.Compute(in);
  double grid_best = kInf;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j)
      grid_best = std::min(grid_best,
                           c.Cost(in.robot, in.goal, {-1.0 + 0.05 * i, -1.0 + 0.05 * j}, nullptr));
  EXPECT_TRUE(out.solved());
  EXPECT_LE(out.cost, grid_best + 0.05) << "COBYLA " << out.cost << " vs grid " << grid_best;
}

TEST(SpanController, ClosedLoopPassesAStandingPedestrianWithoutCollision) {
  SpanController c(nullptr, nullptr, Options());
  const Eigen::MatrixXd rows = Standing({{4.0, 0.0}}, 5);
  UnicycleState s{0, 0, 0};
  const Eigen::Vector2d goal(8, 0);
  double min_gap = kInf;
  int steps = 0;
  for (; steps < 300 && (s.position() - goal).norm() > 0.3; ++steps) {
    NavigationInput in;
    in.robot = s;
    in.goal = goal;
    in.past_rows = &rows;
    s = EulerStep(s, c.Compute(in).command, 0.1);
    min_gap = std::min(min_gap, (s.position() - Eigen::Vector2d(4, 0)).norm() - 0.8);
  }
  EXPECT_LT(steps, 300) << "goal not reached";
  EXPECT_GT(min_gap, 0.0);
}

TEST(SpanController, WithTheMapGoesThroughTheGap) {
  const occupancy::GridMap map = Room(true);
  const StaticCollisionField field(map, 0.4, 0.05);
  SpanController c(nullptr, &field, Options());
  occupancy::MapWorkspace ws = field.MakeWorkspace();
  UnicycleState s{2, 5.75, 0};
  const Eigen::Vector2d goal(9, 5.75);
  int steps = 0;
  bool hit = false;
  for (; steps < 300 && (s.position() - goal).norm() > 0.3; ++steps) {
    NavigationInput in;
    in.robot = s;
    in.goal = goal;
    s = EulerStep(s, c.Compute(in).command, 0.1);
    hit = hit || SweptOccupancy(map, &ws, s.x, s.y, 0.4, 64) > 0.5;
  }
  EXPECT_LT(steps, 300);
  EXPECT_FALSE(hit);
}

TEST(SpanController, NonFiniteObservationsNeverThrow) {
  SpanController c(nullptr, nullptr, Options());
  Eigen::MatrixXd rows = Standing({{2.0, 0.0}, {5.0, 5.0}}, 5);
  rows(0, 9) = std::nan("");
  rows.row(1).setConstant(std::nan(""));
  NavigationInput in;
  in.robot = {0, 0, 0};
  in.goal = {10, 0};
  in.past_rows = &rows;
  const ControlOutcome out = c.Compute(in);
  EXPECT_TRUE(out.solved());
  EXPECT_EQ(c.forecast().pedestrians(),
            1);  // the all-NaN row is dropped, the other stands at its last finite point
  EXPECT_EQ(c.forecast().Mean(0, 1, 0), Eigen::Vector2d(2.0, 0.0));
}

TEST(Baselines, NonFiniteObservationsAreDroppedNotObstacles) {
  Eigen::MatrixXd rows = Standing({{2.0, 0.0}, {5.0, 5.0}}, 5);
  rows.row(1).setConstant(std::nan(""));
  NavigationInput in;
  in.robot = {0, 0, 0};
  in.goal = {10, 0};
  in.past_rows = &rows;
  ReactiveController reactive(nullptr, Options());
  EXPECT_TRUE(reactive.Compute(in).solved());
  const occupancy::GridMap map = Room(false);
  const StaticCollisionField field(map, 0.4, 0.05);
  ClRrtStarOptions o;
  o.max_iterations = 300;
  ClRrtStarController rrt(&field, Eigen::Vector4d(-0.5, 12.5, -0.5, 8.5), o, 2);
  in.robot = {1, 1, 0};
  in.goal = {9, 7};
  const ControlOutcome out = rrt.Compute(in);
  EXPECT_TRUE(out.solved());
  for (Eigen::Index i = 0; i < rrt.path().cols(); ++i) EXPECT_TRUE(rrt.path().col(i).allFinite());
}

// A standing pedestrian 0.45 m ahead, inside the 0.8 m sum of radii: every control collides at
// the first step, so kappa / tau is the same for all of them. The thesis's cost then drives on
// towards the goal, through the pedestrian; the escape fallback backs away.
TEST(SpanController, EscapeBacksAwayWhenEveryControlCollidesAtOnce) {
  const Eigen::MatrixXd rows = Standing({{0.45, 0.0}}, 5);
  NavigationInput in;
  in.robot = {0, 0, 0};
  in.goal = {10, 0};
  in.past_rows = &rows;
  SpanController thesis(nullptr, nullptr, Options());
  ControlOutcome out = thesis.Compute(in);
  EXPECT_NEAR(out.tau, 0.1, 1e-12);
  EXPECT_GT(out.command.v, 0.0);
  EXPECT_EQ(thesis.escapes(), 0);

  SpanControllerOptions o = Options();
  o.escape_tau = 0.1;
  o.escape_horizon = 1.0;
  SpanController escape(nullptr, nullptr, o);
  escape.Forecast(in);
  // Closed form: standing still keeps the contact for all 10 steps; reversing at 1 m/s leaves
  // the disc after three steps (centre distances 0.55, 0.65, 0.75 m, then 0.85 m).
  EXPECT_NEAR(escape.EscapeCost(in.robot, in.goal, {0.0, 0.0}), 1.0 + 1e-3 * 10.0, 1e-12);
  EXPECT_NEAR(escape.EscapeCost(in.robot, in.goal, {-1.0, 0.0}), 0.3 + 1e-3 * 11.0, 1e-12);
  out = escape.Compute(in);
  EXPECT_TRUE(out.solved());
  EXPECT_LT(out.command.v, -0.5);
  EXPECT_EQ(escape.escapes(), 1);
  EXPECT_TRUE(out.fallback);
  // Far from everyone the fallback stays out of the way.
  in.past_rows = nullptr;
  out = escape.Compute(in);
  EXPECT_NEAR(out.command.v, 1.0, 1e-3);
  EXPECT_EQ(escape.escapes(), 1);
  EXPECT_FALSE(out.fallback);
}

TEST(SpanController, BadOptionsAreClearErrors) {
  SpanControllerOptions o;
  o.epsilon = 1.2;
  testing::ExpectErrorContains([&] { SpanController(nullptr, nullptr, o); }, {"epsilon", "1.2"});
  o = SpanControllerOptions();
  o.horizon = 0.0;
  testing::ExpectErrorContains([&] { SpanController(nullptr, nullptr, o); }, {"horizon"});
  o = SpanControllerOptions();
  o.commit_time = 0.05;  // shorter than a step
  testing::ExpectErrorContains([&] { SpanController(nullptr, nullptr, o); },
                               {"commit_time = 0.05", "[dt, horizon]"});
  o = SpanControllerOptions();
  o.escape_tau = -1.0;
  testing::ExpectErrorContains([&] { SpanController(nullptr, nullptr, o); }, {"escape_tau", "-1"});
  o = SpanControllerOptions();
  o.escape_horizon = 5.0;
  EXPECT_EQ(o.Problems(), "");  // the fallback is off: its window is not used
  o.escape_tau = 0.1;
  testing::ExpectErrorContains([&] { SpanController(nullptr, nullptr, o); },
                               {"escape_horizon", "5"});
}

TEST(ReactiveController, StopsWhenBoxedInAndMovesWhenFree) {
  ReactiveController c(nullptr, Options());
  const Eigen::MatrixXd boxed = Standing({{0.75, 0}, {-0.75, 0}, {0, 0.75}, {0, -0.75}}, 5);
  NavigationInput in;
  in.robot = {0, 0, 0};
  in.goal = {10, 0};
  in.past_rows = &boxed;
  ControlOutcome out = c.Compute(in);
  EXPECT_FALSE(out.solved());
  EXPECT_EQ(out.status, ControlStatus::kNoFinitePlan);
  EXPECT_EQ(out.message, "every candidate control collides");
  EXPECT_EQ(out.command.v, 0.0);
  in.past_rows = nullptr;
  out = c.Compute(in);
  EXPECT_TRUE(out.solved());
  EXPECT_GT(out.command.v, 0.9);
}

TEST(PurePursuit, SteersTowardsTheLookaheadPoint) {
  Eigen::Matrix2Xd path(2, 3);
  path << 0, 5, 10, 0, 0, 0;
  const ControlLimits lim;
  Control u = PurePursuit({0, 0, 0}, path, 0.8, lim);
  EXPECT_NEAR(u.v, 1.0, 1e-9);
  EXPECT_NEAR(u.omega, 0.0, 1e-9);
  u = PurePursuit({0, 0.5, 0}, path, 0.8, lim);
  EXPECT_LT(u.omega, 0.0);  // path to the right: turn clockwise
  u = PurePursuit({0, 0, M_PI}, path, 0.8, lim);
  EXPECT_EQ(u.v, 0.0);  // target behind: turn in place
  EXPECT_NE(u.omega, 0.0);
}

TEST(ClRrtStar, PlansThroughTheGapAndStaysPutWhenBlocked) {
  const occupancy::GridMap map = Room(true);
  const StaticCollisionField field(map, 0.4, 0.05);
  ClRrtStarOptions o;
  o.budget_s = 1.0;
  o.max_iterations = 400;
  ClRrtStarController c(&field, Eigen::Vector4d(-0.5, 12.5, -0.5, 8.5), o, 1);
  occupancy::MapWorkspace ws = field.MakeWorkspace();
  UnicycleState s{2, 2, 0};
  const Eigen::Vector2d goal(9, 2);
  int steps = 0;
  bool hit = false;
  for (; steps < 400 && (s.position() - goal).norm() > 0.3; ++steps) {
    NavigationInput in;
    in.robot = s;
    in.goal = goal;
    s = EulerStep(s, c.Compute(in).command, 0.1);
    hit = hit || SweptOccupancy(map, &ws, s.x, s.y, 0.35, 64) > 0.5;
  }
  EXPECT_LT(steps, 400) << "goal not reached; at " << s.x << ", " << s.y;
  EXPECT_FALSE(hit);
  // A goal inside the wall cannot be reached. The partial plan towards it is followed when it
  // makes progress; without accepting partial plans the robot stays put.
  NavigationInput in;
  in.robot = {2, 2, 0};
  in.goal = {5.0, 2.0};
  ControlOutcome out = c.Compute(in);
  EXPECT_TRUE(out.solved());
  EXPECT_GT(out.command.v, 0.0);
  ASSERT_GT(c.path().cols(), 0);
  EXPECT_LT((c.path().col(c.path().cols() - 1) - in.goal).norm(), 1.0);
  o.min_progress = 1e9;
  ClRrtStarController strict(&field, Eigen::Vector4d(-0.5, 12.5, -0.5, 8.5), o, 1);
  out = strict.Compute(in);
  EXPECT_FALSE(out.solved());
  EXPECT_EQ(out.status, ControlStatus::kNoPath);
  EXPECT_FALSE(out.message.empty());
  EXPECT_EQ(out.command.v, 0.0);
  EXPECT_EQ(out.command.omega, 0.0);
}

}  // namespace
}  // namespace foresight::nav
