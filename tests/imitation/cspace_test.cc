// The C-space obstacle transform and system on a 6-DoF test arm written here (always runs):
// the field and the transform's Jacobian against central differences, the inverse round trip,
// the pull-back identities (J_ee q_dot = f_world, J_o p_dot = q_dot_inner) against the closed
// form of a straight-line attractor, a rollout that keeps every ball of the arm out of a fitted
// spherical obstacle (exact distances), no allocation (speed: `foresight bench ARTIFACT`).

#include "inference/imitation/cspace.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "models/imitation/occupancy_fit.h"
#define FORESIGHT_ALLOC_COUNTER_MALLOC  // count Eigen's malloc too
#include "tests/alloc_counter.h"        // replaces operator new: one per binary
#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::MatricesNear;

// An anthropomorphic 6-DoF arm, straight up at q = 0: base yaw, shoulder and elbow pitch (0.4 m
// upper arm), forearm roll, wrist pitch, flange roll; tool 0.1 m beyond the flange (1.1 m tall).
const char* kArmUrdf = R"(<?xml version="1.0"?>
<robot name="test_arm">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/>
  <link name="l5"/><link name="l6"/><link name="tool"/>
  <joint name="yaw" type="continuous"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/></joint>
  <joint name="shoulder" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
    <limit lower="-2.8" upper="2.8" effort="1" velocity="1"/></joint>
  <joint name="roll" type="continuous"><parent link="l3"/><child link="l4"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/></joint>
  <joint name="wrist" type="revolute"><parent link="l4"/><child link="l5"/>
    <origin xyz="0 0 0.15"/><axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="flange" type="continuous"><parent link="l5"/><child link="l6"/>
    <origin xyz="0 0 0.05"/><axis xyz="0 0 1"/></joint>
  <joint name="tool_mount" type="fixed"><parent link="l6"/><child link="tool"/>
    <origin xyz="0 0 0.1"/></joint>
</robot>
)";

/// Ten balls of radius 0.04 m: four on the upper arm, three on the forearm, two on the wrist, one
/// at the tool.
std::vector<BodyPoint> ArmPoints() {
  constexpr double r = 0.04;
  return {{"l2", {0, 0, 0.08}, r}, {"l2", {0, 0, 0.16}, r}, {"l2", {0, 0, 0.24}, r},
          {"l2", {0, 0, 0.32}, r}, {"l3", {0, 0, 0.0}, r},  {"l3", {0, 0, 0.1}, r},
          {"l3", {0, 0, 0.2}, r},  {"l4", {0, 0, 0.1}, r},  {"l5", {0, 0, 0.05}, r},
          {"tool", {0, 0, 0}, r}};
}

SerialChain Arm() {
  return SerialChain::FromText(kArmUrdf, "test_arm.urdf", "base", "tool", ArmPoints());
}

// The obstacle: a ball of radius 0.075 m (the thesis's 15 cm) whose occupancy is fitted inflated
// by the body-ball radius, so that centres kept out of the fitted obstacle keep the balls out.
struct Obstacle {
  Eigen::Vector3d centre;
  double radius = 0.075;
};

/// A Hilbert map of the inflated obstacle: 0.1 m grid, gamma 100, cut-off 0.39 m (a 7^3 window;
/// the truncation jump exp(-gamma r_c^2) = 3e-7 is below what the finite differences resolve),
/// fitted to a 0.05 m lattice of occupancy samples.
OccupancyField<3> FitObstacle(const Obstacle& obstacle, double inflate) {
  const double R = obstacle.radius + inflate;
  const Vec<3> lo = obstacle.centre.array() - (R + 0.15);
  const Vec<3> hi = obstacle.centre.array() + (R + 0.15);
  const RbfGrid<3> grid(RbfGrid<3>::Covering(lo, hi, 0.0, 0.1, 100, 0.39), "obstacle grid");
  Eigen::Matrix<double, 3, Eigen::Dynamic> points;
  std::vector<std::uint8_t> occupied;
  const Eigen::Vector3d c = obstacle.centre;
  SampleObstacleOccupancy<3>([c, R](const Vec<3>& s) { return (s - c).norm() - R; }, lo, hi, 0.05,
                             &points, &occupied);
  return FitOccupancyField<3>(grid, points, occupied, 1.0, "obstacle fit");
}

/// The straight-line attractor: an ImitationSystem with zero weights (psi_i = identity), so
/// f_i(s) = -speed (s - s_goal) / ||s - s_goal||.
ImitationSystem<3> StraightLine(const Vec<3>& goal_model, double speed) {
  RbfGridSpec<3> spec;
  spec.lower = Vec<3>::Constant(-1);
  spec.counts = {3, 3, 3};
  spec.spacing = 1;
  spec.gamma = 1;
  spec.cutoff_radius = 1.5;
  const RbfGrid<3> grid(spec, "attractor grid");
  return ImitationSystem<3>(RbfFlow<3>(grid, Eigen::MatrixXd::Zero(grid.size(), 3), {1.0, 10}),
                            goal_model, speed);
}

// ---- the scenario -----------------------------------------------------------------------------

const ArmVector kStart = (ArmVector() << -0.9, 0.5, 1.1, 0.0, 0.9, 0.0).finished();
/// The goal: the end effector of the start configuration turned by 1.8 rad about the base.
const Eigen::Vector3d kGoal = [] {
  const SerialChain chain = Arm();
  ChainData data = chain.MakeData();
  ArmVector q = kStart;
  q[0] += 1.8;
  Kinematics(chain, q, &data);
  return Eigen::Vector3d(data.p_ee);
}();
const TaskNormalisation kNormalisation{Eigen::Vector3d(0.2, 0.1, 0.5), 2.0};
constexpr double kSpeed = 0.4;  // model units/s: 0.2 m/s in the world

CSpaceSystem PlainSystem(double damping = CSpaceSystem::kDefaultDamping) {
  return CSpaceSystem(Arm(), StraightLine(kNormalisation.ToModel(kGoal), kSpeed), kNormalisation,
                      std::nullopt, damping);
}

/// Min over the path and the balls of ||x_j - c|| - (R + r_j): > 0 is collision-free.
double Clearance(const SerialChain& chain, const Eigen::Matrix<double, kArmDof, -1>& path,
                 const Obstacle& obstacle, int* worst_point = nullptr) {
  ChainData data = chain.MakeData();
  double clearance = 1e9;
  for (Eigen::Index i = 0; i < path.cols(); ++i) {
    Kinematics(chain, path.col(i), &data);
    for (int j = 0; j < chain.num_points(); ++j) {
      const double d = (data.p.col(j) - obstacle.centre).norm() - obstacle.radius -
                       chain.points()[static_cast<size_t>(j)].radius;
      if (d < clearance) {
        clearance = d;
        if (worst_point != nullptr) *worst_point = j;
      }
    }
  }
  return clearance;
}

/// The obstacle sits on the path of the elbow ball of the unmodified rollout (point 4, half way),
/// raised by 0.06 m: the plain path still runs 0.055 m deep into it, and the field is not
/// symmetric about the path.
struct Scenario {
  Obstacle obstacle;
  OccupancyField<3> field;
  CSpaceRollout plain;
};

const Scenario& TheScenario() {
  static const Scenario scenario = [] {
    Scenario s;
    RolloutSettings settings;
    settings.dt = 0.02;
    settings.max_steps = 1000;
    settings.goal_tolerance = 0.01;
    s.plain = RollOutCSpace(PlainSystem(), kStart, settings);
    const SerialChain chain = Arm();
    ChainData data = chain.MakeData();
    Kinematics(chain, s.plain.joints.col(s.plain.joints.cols() / 2), &data);
    s.obstacle.centre = data.p.col(4) + Eigen::Vector3d(0, 0, 0.06);
    s.field = FitObstacle(s.obstacle, 0.04);
    return s;
  }();
  return scenario;
}

CSpaceObstacleTransform Transform(double time, int steps) {
  return CSpaceObstacleTransform(Arm(), TheScenario().field, {time, steps});
}

/// The Jacobian of `f` at q by central differences of step 1e-6 rad.
template <typename F>
ArmMatrix CentralDifferences(const F& f, const ArmVector& q) {
  constexpr double h = 1e-6;
  ArmMatrix out;
  for (int k = 0; k < kArmDof; ++k) {
    const ArmVector e = ArmVector::Unit(k) * h;
    out.col(k) = (f(q + e) - f(q - e)) / (2 * h);
  }
  return out;
}

// ---- the field and the transform --------------------------------------------------------------

/// Configurations of the plain rollout near the obstacle (where the field is not negligible).
std::vector<ArmVector> ConfigurationsNearTheObstacle() {
  const CSpaceRollout& plain = TheScenario().plain;
  std::vector<ArmVector> out;
  for (int f = 2; f <= 6; ++f) out.push_back(plain.joints.col(plain.joints.cols() * f / 15));
  return out;
}

TEST(CSpaceObstacleTransform, FieldIsTheGradientOfTheOccupancyAndItsJacobianMatches) {
  const CSpaceObstacleTransform transform = Transform(0.2, 40);
  CSpaceTransformWorkspace ws = transform.MakeWorkspace();
  int informative = 0;
  for (const ArmVector& q : ConfigurationsNearTheObstacle()) {
    ArmMatrix dV;
    double occupancy = 0;
    const ArmVector V = transform.Field(q, &ws, &dV, &occupancy);
    if (V.norm() > 1e-2) ++informative;
    constexpr double h = 1e-6;
    ArmVector V_fd;
    ArmMatrix dV_fd;
    for (int k = 0; k < kArmDof; ++k) {
      const ArmVector e = ArmVector::Unit(k) * h;
      double plus = 0, minus = 0;
      const ArmVector Vp = transform.Field(q + e, &ws, nullptr, &plus);
      const ArmVector Vm = transform.Field(q - e, &ws, nullptr, &minus);
      V_fd[k] = (plus - minus) / (2 * h);
      dV_fd.col(k) = (Vp - Vm) / (2 * h);
    }
    EXPECT_TRUE(MatricesNear(V, V_fd, 1e-6 * (1 + V.cwiseAbs().maxCoeff())));
    EXPECT_TRUE(MatricesNear(dV, dV_fd, 1e-5 * (1 + dV.cwiseAbs().maxCoeff())));
  }
  EXPECT_GE(informative, 2) << "the rollout should pass through the field";
}

// The goal gate: w V_q with w = 1 - exp(-r^2 / (2 l^2)); its Jacobian against central
// differences where w varies (a goal 5 cm from the end effector, l = 4 cm), and the field and the
// flow are exactly zero / the identity where the end effector is at the goal.
TEST(CSpaceObstacleTransform, GoalGateVanishesAtTheGoalAndItsJacobianMatches) {
  const SerialChain chain = Arm();
  ChainData data = chain.MakeData();
  const CSpaceObstacleTransform plain = Transform(0.2, 40);
  CSpaceTransformWorkspace ws = plain.MakeWorkspace();
  int informative = 0;
  for (const ArmVector& q : ConfigurationsNearTheObstacle()) {
    Kinematics(chain, q, &data);
    GoalGate gate;
    gate.goal = data.p_ee + Eigen::Vector3d(0.03, -0.04, 0.0);
    gate.length = 0.04;
    const CSpaceObstacleTransform gated(chain, TheScenario().field, {0.2, 40}, gate);
    ArmMatrix dV;
    const ArmVector V = gated.Field(q, &ws, &dV);
    const double w = 1 - std::exp(-0.05 * 0.05 / (2 * 0.04 * 0.04));
    EXPECT_TRUE(MatricesNear(V, w * plain.Field(q, &ws), 1e-12 * (1 + V.norm())));
    if (V.norm() > 1e-2) ++informative;
    const ArmMatrix dV_fd =
        CentralDifferences([&](const ArmVector& x) { return gated.Field(x, &ws); }, q);
    EXPECT_TRUE(MatricesNear(dV, dV_fd, 1e-5 * (1 + dV.cwiseAbs().maxCoeff())));
    // A gate at this configuration's own end effector: V = 0 and psi_o(q) = q.
    gate.goal = data.p_ee;
    const CSpaceObstacleTransform at_goal(chain, TheScenario().field, {0.2, 40}, gate);
    EXPECT_EQ(at_goal.Field(q, &ws).norm(), 0.0);
    EXPECT_TRUE(MatricesNear(at_goal.Forward(q, &ws), q, 0));
  }
  EXPECT_GE(informative, 2) << "the rollout should pass through the field";
  GoalGate bad;
  bad.length = -1;
  ExpectErrorContains(
      [&] {
        CSpaceObstacleTransform(chain, TheScenario().field, {1, 10}, bad);
      },
      {"goal gate", "-1"});
}

TEST(CSpaceObstacleTransform, JacobianMatchesFiniteDifferences) {
  const CSpaceObstacleTransform transform = Transform(0.2, 40);
  CSpaceTransformWorkspace ws = transform.MakeWorkspace();
  for (const ArmVector& p : ConfigurationsNearTheObstacle()) {
    ArmMatrix J;
    const ArmVector q = transform.Forward(p, &ws, &J);
    EXPECT_GT((q - p).norm(), 0) << "the flow moves configurations near the obstacle";
    const ArmMatrix J_fd =
        CentralDifferences([&](const ArmVector& x) { return transform.Forward(x, &ws); }, p);
    EXPECT_TRUE(MatricesNear(J, J_fd, 1e-6 * (1 + J.cwiseAbs().maxCoeff())));
  }
}

// Forward stops once V_q is exactly zero (no body point within the map's support): the result must
// equal every Euler step taken, with the same values, with and without the goal gate.
TEST(CSpaceObstacleTransform, StoppingOutsideTheSupportGivesTheFullFlowExactly) {
  const int steps = 30;
  const double h = 0.2 / steps;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> angle(-2.5, 2.5);
  std::vector<ArmVector> qs;
  for (int n = 0; n < 60; ++n) {
    ArmVector q;
    for (int k = 0; k < kArmDof; ++k) q[k] = angle(rng);
    qs.push_back(q);
  }
  // An obstacle off to one side, so that the arm can turn every body point out of the support
  // (the cube 0.66 m around it); the scenario's near the elbow covers every configuration.
  Obstacle aside;
  aside.centre = Eigen::Vector3d(0.8, 0, 0.6);
  const OccupancyField<3> field = FitObstacle(aside, 0.04);
  // With the gate, its goal is the end effector of the first configuration whose field is not
  // zero: the gate closes there (V = 0 and dV = 0 with a map under the arm).
  Eigen::Vector3d gate_goal(0.3, 0.2, 0.5);
  {
    const CSpaceObstacleTransform open(Arm(), field, {0.2, steps});
    CSpaceTransformWorkspace ws = open.MakeWorkspace();
    for (const ArmVector& q : qs)
      if (!open.Field(q, &ws).isZero(0)) {
        gate_goal = ws.chain.p_ee;
        break;
      }
  }
  for (double gate : {0.0, 0.1}) {
    const CSpaceObstacleTransform transform(Arm(), field, {0.2, steps}, {gate_goal, gate});
    CSpaceTransformWorkspace ws = transform.MakeWorkspace();
    int outside = 0;
    for (const ArmVector& p : qs) {
      ArmVector q = p;  // every step
      ArmMatrix J = ArmMatrix::Identity(), dV;
      for (int k = 0; k < steps; ++k) {
        const ArmVector V = transform.Field(q, &ws, &dV);
        J = (ArmMatrix::Identity() + h * dV) * J;
        q += h * V;
      }
      ArmMatrix jacobian;
      EXPECT_TRUE(MatricesNear(transform.Forward(p, &ws, &jacobian), q, 0)) << p.transpose();
      EXPECT_TRUE(MatricesNear(jacobian, J, 0)) << p.transpose();
      EXPECT_TRUE(MatricesNear(transform.Forward(p, &ws), q, 0)) << p.transpose();
      outside += transform.Field(p, &ws).isZero(0) ? 1 : 0;
    }
    if (gate > 0) {  // the configuration at the gate's goal: the field is closed there
      ArmMatrix dV;
      bool closed = false;
      for (const ArmVector& p : qs) {
        const ArmVector V = transform.Field(p, &ws, &dV);
        if ((ws.chain.p_ee - gate_goal).norm() == 0) closed = V.isZero(0) && dV.isZero(0);
      }
      EXPECT_TRUE(closed);
    }
    EXPECT_GE(outside, 5) << "configurations with every body point outside the map's support";
    EXPECT_LE(outside, static_cast<int>(qs.size()) - 5);
  }
}

TEST(CSpaceObstacleTransform, InverseRoundTrips) {
  // h = 0.005: h |dV_q| < 1 on these configurations, so every step's fixed point contracts.
  const CSpaceObstacleTransform transform = Transform(0.2, 40);
  CSpaceTransformWorkspace ws = transform.MakeWorkspace();
  for (const ArmVector& x : ConfigurationsNearTheObstacle()) {
    ArmVector p;
    ArmMatrix J;
    ASSERT_TRUE(transform.Inverse(transform.Forward(x, &ws, &J), &ws, &p));
    // Each step is solved to 1e-12 in q; back in p that error grows by up to ||J_o^-1||.
    EXPECT_TRUE(MatricesNear(p, x, 1e-11 * (1 + J.inverse().norm())));
    ASSERT_TRUE(transform.Inverse(x, &ws, &p));
    EXPECT_TRUE(MatricesNear(transform.Forward(p, &ws), x, 1e-10));
  }
}

TEST(CSpaceObstacleTransform, InverseReportsNonInvertibleSettings) {
  // One Euler step of h = 50: h Lip(V_q) >> 1 near the obstacle, so the fixed point diverges.
  const CSpaceObstacleTransform transform = Transform(50, 1);
  CSpaceTransformWorkspace ws = transform.MakeWorkspace();
  int failures = 0;
  for (const ArmVector& q : ConfigurationsNearTheObstacle()) {
    ArmVector p;
    failures += transform.Inverse(q, &ws, &p) ? 0 : 1;
  }
  EXPECT_GE(failures, 1);
}

// ---- the system ---------------------------------------------------------------------------------

TEST(CSpaceSystem, WithoutObstacleTheEndEffectorFollowsTheImitationSystem) {
  const CSpaceSystem exact = PlainSystem(0.0), damped = PlainSystem();
  CSpaceSystemWorkspace ws = exact.MakeWorkspace();
  ChainData data = exact.chain().MakeData();
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0, 0.4);
  for (int trial = 0; trial < 10; ++trial) {
    ArmVector q = kStart;
    for (int k = 0; k < kArmDof; ++k) q[k] += noise(rng);
    Kinematics(exact.chain(), q, &data);
    // Closed form of the straight-line attractor in the world: speed / scale toward the goal.
    const Eigen::Vector3d f = -kSpeed / kNormalisation.scale * (data.p_ee - kGoal).normalized();
    EXPECT_TRUE(MatricesNear(exact.TaskVelocity(data.p_ee, &ws), f, 1e-12));
    EXPECT_TRUE(MatricesNear(exact.Velocity(q, &ws), exact.InnerVelocity(q, &ws), 0));
    EXPECT_TRUE(MatricesNear(data.J_ee * exact.Velocity(q, &ws), f, 1e-9));
    // lambda = 1e-3 m: J J^+ = J J' (J J' + lambda^2 I)^-1 departs from I by ~(lambda / sigma)^2.
    EXPECT_TRUE(MatricesNear(data.J_ee * damped.Velocity(q, &ws), f, 1e-3 * f.norm()));
  }
  EXPECT_TRUE(MatricesNear(exact.goal(), kGoal, 1e-12));
}

TEST(CSpaceSystem, WithObstacleTheOuterVelocityPullsBackTheInnerOne) {
  const CSpaceSystem system(Arm(), StraightLine(kNormalisation.ToModel(kGoal), kSpeed),
                            kNormalisation, Transform(0.3, 20));
  CSpaceSystemWorkspace ws = system.MakeWorkspace();
  CSpaceTransformWorkspace tws = system.obstacle()->MakeWorkspace();
  for (const ArmVector& p : ConfigurationsNearTheObstacle()) {
    ArmMatrix J_o;
    const ArmVector q = system.obstacle()->Forward(p, &tws, &J_o);
    EXPECT_TRUE(MatricesNear(system.Inner(p, &ws), q, 0));
    const ArmVector inner = system.InnerVelocity(q, &ws);
    const ArmVector outer = system.Velocity(p, &ws);
    EXPECT_GT((outer - inner).norm(), 1e-6) << "the transform changes the velocity here";
    // p_dot solves J_o p_dot = q_dot by LU: residual ~ machine epsilon x cond(J_o).
    const Eigen::JacobiSVD<ArmMatrix> svd(J_o);
    const double cond = svd.singularValues()(0) / svd.singularValues()(kArmDof - 1);
    EXPECT_TRUE(MatricesNear(J_o * outer, inner, 1e-13 * cond * (1 + inner.norm())));
  }
}

TEST(CSpaceSystem, RolloutKeepsEveryBallOutOfTheObstacleAndReachesTheGoal) {
  const Scenario& s = TheScenario();
  RolloutSettings settings;
  settings.dt = 0.02;
  settings.max_steps = 1000;
  settings.goal_tolerance = 0.01;
  // The premise: the plain system reaches the goal through the obstacle.
  ASSERT_TRUE(s.plain.reached()) << CSpaceStopName(s.plain.stop);
  int worst = -1;
  EXPECT_LT(Clearance(Arm(), s.plain.joints, s.obstacle, &worst), -0.03);
  EXPECT_NE(worst, 9) << "a body point of the arm, not the tool, hits the obstacle";

  // T = 0.3 and K = 20 (T from 0.2 to 0.3 with K from 10 to 30 all avoid and reach here; from
  // T = 0.4 on the flow also moves the goal configuration, so the end effector stops short).
  const CSpaceSystem avoiding(Arm(), StraightLine(kNormalisation.ToModel(kGoal), kSpeed),
                              kNormalisation, Transform(0.3, 20));
  const CSpaceRollout rollout = RollOutCSpace(avoiding, kStart, settings);
  EXPECT_TRUE(rollout.reached()) << CSpaceStopName(rollout.stop);
  EXPECT_GT(Clearance(Arm(), rollout.joints, s.obstacle), 0);
  EXPECT_LE((rollout.end_effector.rightCols<1>() - kGoal).norm(), settings.goal_tolerance);
  std::printf(
      "plain: %ld steps, clearance %.3f m; avoiding: %ld steps, clearance %.3f m\n",
      static_cast<long>(s.plain.joints.cols()), Clearance(Arm(), s.plain.joints, s.obstacle),
      static_cast<long>(rollout.joints.cols()), Clearance(Arm(), rollout.joints, s.obstacle));
}

TEST(CSpaceSystem, VelocityAllocatesNothing) {
  // Speed is measured by `foresight bench ARTIFACT`, not here. K = 10 Euler steps, 10 body points,
  // a 5^3 window of inducing states per field query (the fitted weights with the cut-off at 0.29
  // m).
  const OccupancyField<3>& fitted = TheScenario().field;
  RbfGridSpec<3> spec = fitted.grid().spec();
  spec.cutoff_radius = 0.29;
  const OccupancyField<3> field(RbfGrid<3>(spec), fitted.weights(), fitted.bias());
  const CSpaceSystem system(Arm(), StraightLine(kNormalisation.ToModel(kGoal), kSpeed),
                            kNormalisation, CSpaceObstacleTransform(Arm(), field, {0.3, 10}));
  CSpaceSystemWorkspace ws = system.MakeWorkspace();
  const std::vector<ArmVector> configurations = ConfigurationsNearTheObstacle();
  ArmVector sum = system.Velocity(configurations[0], &ws);  // warm up
  constexpr int kRepeats = 200;
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < kRepeats; ++i)
    sum += system.Velocity(configurations[static_cast<size_t>(i) % configurations.size()], &ws);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(sum.allFinite());
}

// ---- bad input ----------------------------------------------------------------------------------

TEST(CSpaceErrors, NameTheOffendingValue) {
  const OccupancyField<3>& field = TheScenario().field;
  ExpectErrorContains(
      [&] {
        CSpaceObstacleTransform(Arm(), field, {0.0, 10});
      },
      {"flow time", "0"});
  ExpectErrorContains([&] { CSpaceObstacleTransform(Arm(), field, {1.0, 0}); }, {"steps", "0"});
  ExpectErrorContains(
      [&] {
        CSpaceObstacleTransform(
            SerialChain::FromText(kArmUrdf, "test_arm.urdf", "base", "tool", {}), field, {1.0, 10});
      },
      {"no body points"});
  const ImitationSystem<3> attractor = StraightLine(Vec<3>::Zero(), 1);
  ExpectErrorContains(
      [&] {
        CSpaceSystem(Arm(), attractor, {Eigen::Vector3d::Zero(), 0.0});
      },
      {"scale", "0"});
  ExpectErrorContains(
      [&] { CSpaceSystem(Arm(), attractor, TaskNormalisation{}, std::nullopt, -1); },
      {"damping", "-1"});
  std::string renamed = kArmUrdf;
  renamed.replace(renamed.find("\"wrist\""), 7, "\"pitch\"");
  const SerialChain other =
      SerialChain::FromText(renamed, "renamed.urdf", "base", "tool", ArmPoints());
  ExpectErrorContains(
      [&] {
        CSpaceSystem(Arm(), attractor, TaskNormalisation{},
                     CSpaceObstacleTransform(other, field, {1.0, 10}));
      },
      {"joint 5", "'pitch'", "'wrist'"});
  RolloutSettings bad;
  bad.dt = 0;
  ExpectErrorContains([&] { RollOutCSpace(PlainSystem(), kStart, bad); }, {"dt", "0"});
}

}  // namespace
}  // namespace foresight::imitation
