#include "inference/manipulation/planners.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

using testing::ExpectErrorContains;

const JointVector kLower = JointVector::Constant(-2.0);
const JointVector kUpper = JointVector::Constant(2.0);
constexpr double kResolution = 0.05;

/// A wall slab |q0| < 0.2 across the joint box, open only through the window |q1 - 0.8| < 0.3.
bool WallWithWindow(const JointVector& q) {
  return !(std::abs(q(0)) < 0.2 && std::abs(q(1) - 0.8) >= 0.3);
}

JointVector Start() {
  JointVector q = JointVector::Zero();
  q(0) = -1.0;
  return q;
}
JointVector Goal() {
  JointVector q = JointVector::Zero();
  q(0) = 1.0;
  q(2) = 0.5;
  return q;
}

PlannerOptions Options(double budget_s, std::uint32_t seed = 1) {
  PlannerOptions o;
  o.time_budget_s = budget_s;
  o.resolution_rad = kResolution;
  o.seed = seed;
  return o;
}

bool WithinLimits(const Eigen::VectorXd& q) {
  return (q.array() >= kLower.array()).all() && (q.array() <= kUpper.array()).all();
}

/// Independent check of a path: every waypoint and the states at fractions j / n, n = ceil(|d| /
/// resolution), of every segment pass `is_valid`; the ends are start and goal.
::testing::AssertionResult PathIsValid(const Eigen::MatrixXd& w,
                                       const std::function<bool(const JointVector&)>& is_valid,
                                       const JointVector& start, const JointVector& goal) {
  if (w.rows() != kDof || w.cols() < 2)
    return ::testing::AssertionFailure()
           << "waypoints are [" << w.rows() << " x " << w.cols() << "]";
  if ((w.col(0) - start).norm() > 1e-12 || (w.col(w.cols() - 1) - goal).norm() > 1e-12)
    return ::testing::AssertionFailure() << "path does not start at start and end at goal";
  for (Eigen::Index k = 0; k < w.cols(); ++k) {
    if (!is_valid(w.col(k))) return ::testing::AssertionFailure() << "waypoint " << k << " invalid";
    if (!WithinLimits(w.col(k)))
      return ::testing::AssertionFailure() << "waypoint " << k << " outside the limits";
  }
  for (Eigen::Index k = 0; k + 1 < w.cols(); ++k) {
    const JointVector a = w.col(k), d = w.col(k + 1) - w.col(k);
    const int n = static_cast<int>(std::ceil(d.norm() / kResolution));
    for (int j = 1; j <= n; ++j) {
      const JointVector q = a + d * (static_cast<double>(j) / n);
      if (!is_valid(q))
        return ::testing::AssertionFailure()
               << "segment " << k << " state " << j << "/" << n << " invalid: " << q.transpose();
    }
  }
  return ::testing::AssertionSuccess();
}

double Length(const Eigen::MatrixXd& w) {
  double length = 0;
  for (Eigen::Index k = 1; k < w.cols(); ++k) length += (w.col(k) - w.col(k - 1)).norm();
  return length;
}

class EveryPlanner : public ::testing::TestWithParam<PlannerKind> {};

TEST_P(EveryPlanner, FindsAValidPathThroughTheWindow) {
  const double budget = GetParam() == PlannerKind::kBitStar ? 0.3 : 2.0;
  const PlannerResult r =
      Plan(GetParam(), Start(), Goal(), kLower, kUpper, WallWithWindow, Options(budget));
  ASSERT_TRUE(r.solved()) << r.BriefReport();
  EXPECT_TRUE(r.message.empty());
  EXPECT_TRUE(PathIsValid(r.waypoints, WallWithWindow, Start(), Goal()));
  // The path crosses the wall, so it passes through the window.
  bool through_window = false;
  for (Eigen::Index k = 0; k + 1 < r.waypoints.cols(); ++k)
    if (r.waypoints(0, k) < 0 && r.waypoints(0, k + 1) >= 0) through_window = true;
  EXPECT_TRUE(through_window);
  EXPECT_GT(r.collision_checks, 2);
  EXPECT_GT(r.planning_time_s, 0.0);
  if (GetParam() == PlannerKind::kBitStar) {
    EXPECT_GE(r.planning_time_s, 0.9 * budget) << "BIT* should use its whole budget";
  } else {
    EXPECT_LT(r.planning_time_s, budget) << "should stop at the first solution";
  }
}

TEST_P(EveryPlanner, InvalidStartOrGoalIsAStatus) {
  JointVector in_wall = Start();
  in_wall(0) = 0.0;
  PlannerResult r = Plan(GetParam(), in_wall, Goal(), kLower, kUpper, WallWithWindow, Options(0.1));
  EXPECT_EQ(r.status, PlannerStatus::kInvalidStart) << r.BriefReport();
  EXPECT_NE(r.message.find("not valid"), std::string::npos) << r.message;
  EXPECT_EQ(r.waypoints.cols(), 0);
  EXPECT_EQ(r.collision_checks, 1);

  JointVector outside = Start();
  outside(3) = 2.5;
  r = Plan(GetParam(), outside, Goal(), kLower, kUpper, WallWithWindow, Options(0.1));
  EXPECT_EQ(r.status, PlannerStatus::kInvalidStart);
  EXPECT_NE(r.message.find("outside the joint limits"), std::string::npos) << r.message;

  r = Plan(GetParam(), Start(), in_wall, kLower, kUpper, WallWithWindow, Options(0.1));
  EXPECT_EQ(r.status, PlannerStatus::kInvalidGoal) << r.BriefReport();
}

TEST_P(EveryPlanner, EnclosedGoalIsNotSolvedAndDoesNotThrow) {
  // A hollow cube (infinity-norm shell 0.3 < |q - goal| < 0.5) around a valid goal.
  const JointVector goal = Goal();
  const auto enclosed = [goal](const JointVector& q) {
    const double r = (q - goal).cwiseAbs().maxCoeff();
    return !(r > 0.3 && r < 0.5);
  };
  PlannerResult r;
  EXPECT_NO_THROW(r = Plan(GetParam(), Start(), goal, kLower, kUpper, enclosed, Options(0.2)));
  EXPECT_FALSE(r.solved()) << r.BriefReport();
  EXPECT_TRUE(r.status == PlannerStatus::kTimeout || r.status == PlannerStatus::kApproximate)
      << r.BriefReport();
  EXPECT_EQ(r.waypoints.cols(), 0);
  EXPECT_LT(r.planning_time_s, 1.0);
}

TEST_P(EveryPlanner, ExceptionInTheValidityFunctionIsAnErrorStatus) {
  int calls = 0;
  const auto throwing = [&calls](const JointVector& q) {
    if (++calls > 10) throw std::runtime_error("validity checker broke");
    return WallWithWindow(q);
  };
  PlannerResult r;
  EXPECT_NO_THROW(r = Plan(GetParam(), Start(), Goal(), kLower, kUpper, throwing, Options(0.5)));
  EXPECT_EQ(r.status, PlannerStatus::kError);
  EXPECT_NE(r.message.find("validity checker broke"), std::string::npos) << r.message;
  EXPECT_EQ(r.collision_checks, 11);
}

INSTANTIATE_TEST_SUITE_P(Planners, EveryPlanner,
                         ::testing::Values(PlannerKind::kBiEst, PlannerKind::kBitStar,
                                           PlannerKind::kRrtConnect),
                         [](const ::testing::TestParamInfo<PlannerKind>& param) {
                           return std::string(PlannerName(param.param));
                         });

TEST(Plan, SameSeedSamePath) {
  // Relies on OMPL re-seeding its seed generator on every setSeed (see planners.h).
  for (PlannerKind kind : {PlannerKind::kRrtConnect, PlannerKind::kBiEst}) {
    const PlannerResult a =
        Plan(kind, Start(), Goal(), kLower, kUpper, WallWithWindow, Options(2.0, 7));
    const PlannerResult b =
        Plan(kind, Start(), Goal(), kLower, kUpper, WallWithWindow, Options(2.0, 7));
    const PlannerResult c =
        Plan(kind, Start(), Goal(), kLower, kUpper, WallWithWindow, Options(2.0, 8));
    ASSERT_TRUE(a.solved() && b.solved() && c.solved()) << PlannerName(kind);
    ASSERT_EQ(a.waypoints.cols(), b.waypoints.cols()) << PlannerName(kind);
    EXPECT_TRUE(testing::MatricesNear(a.waypoints, b.waypoints, 0)) << PlannerName(kind);
    EXPECT_EQ(a.collision_checks, b.collision_checks) << PlannerName(kind);
    EXPECT_FALSE(a.waypoints.cols() == c.waypoints.cols() &&
                 testing::MatricesNear(a.waypoints, c.waypoints, 1e-12))
        << PlannerName(kind) << ": seed 8 gave the path of seed 7";
  }
}

TEST(Plan, BitStarLongerBudgetIsNoLonger) {
  // Same seed: the longer run continues the shorter run's sequence, and BIT* only keeps better
  // solutions, so its path is no longer.
  const PlannerResult short_run =
      Plan(PlannerKind::kBitStar, Start(), Goal(), kLower, kUpper, WallWithWindow, Options(0.3, 3));
  const PlannerResult long_run =
      Plan(PlannerKind::kBitStar, Start(), Goal(), kLower, kUpper, WallWithWindow, Options(1.0, 3));
  ASSERT_TRUE(short_run.solved() && long_run.solved());
  EXPECT_LE(Length(long_run.waypoints), Length(short_run.waypoints) + 1e-9);
  EXPECT_GT(long_run.collision_checks, short_run.collision_checks);
  // The optimum goes through the window corner: at least the straight-line distance.
  EXPECT_GE(Length(long_run.waypoints), (Goal() - Start()).norm());
}

TEST(Plan, SimplifyKeepsThePathValidAndShortensIt) {
  PlannerOptions options = Options(2.0, 5);
  const PlannerResult raw =
      Plan(PlannerKind::kRrtConnect, Start(), Goal(), kLower, kUpper, WallWithWindow, options);
  options.simplify = true;
  const PlannerResult simplified =
      Plan(PlannerKind::kRrtConnect, Start(), Goal(), kLower, kUpper, WallWithWindow, options);
  ASSERT_TRUE(raw.solved() && simplified.solved());
  EXPECT_TRUE(PathIsValid(simplified.waypoints, WallWithWindow, Start(), Goal()));
  EXPECT_LE(Length(simplified.waypoints), Length(raw.waypoints) + 1e-9);
  EXPECT_GT(simplified.collision_checks, raw.collision_checks);
}

TEST(Plan, BadInputIsAnError) {
  PlannerOptions options = Options(1.0);
  options.resolution_rad = 0;
  options.seed = 0;
  ExpectErrorContains(
      [&] { Plan(PlannerKind::kBiEst, Start(), Goal(), kLower, kUpper, WallWithWindow, options); },
      {"resolution_rad = 0", "seed = 0"});
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_TRUE(Options(1.0).IsValid());
  ExpectErrorContains(
      [&] {
        Plan(PlannerKind::kBiEst, Start(), Goal(), kUpper, kLower, WallWithWindow, Options(1.0));
      },
      {"joint limits", "lower < upper"});
  ExpectErrorContains(
      [&] { Plan(PlannerKind::kBiEst, Start(), Goal(), kLower, kUpper, nullptr, Options(1.0)); },
      {"no validity function"});
}

TEST(PlannerOptions, ConfigRoundTripAndStrictRead) {
  PlannerOptions o = Options(1.2, 42);
  o.simplify = true;
  o.range_rad = 0.5;
  const PlannerOptions back =
      config::FromYaml<PlannerOptions>(config::ParseYaml(config::ToYaml(o), "test"), "test");
  EXPECT_EQ(back.time_budget_s, 1.2);
  EXPECT_EQ(back.resolution_rad, kResolution);
  EXPECT_TRUE(back.simplify);
  EXPECT_EQ(back.seed, 42u);
  EXPECT_EQ(back.range_rad, 0.5);
  ExpectErrorContains(
      [] { config::FromYaml<PlannerOptions>(config::ParseYaml("seed: 0", "test"), "test"); },
      {"seed"});
  ExpectErrorContains(
      [] { config::FromYaml<PlannerOptions>(config::ParseYaml("budget: 1", "test"), "test"); },
      {"budget"});
  EXPECT_NE(config::ReferenceTable<PlannerOptions>().find("resolution_rad"), std::string::npos);
}

TEST(PlannerKind, NamesRoundTrip) {
  for (const auto& [kind, name] : PlannerKindNames()) {
    EXPECT_EQ(ParsePlannerKind(name), kind);
    EXPECT_STREQ(PlannerName(kind), name);
  }
  ExpectErrorContains([] { ParsePlannerKind("rrtstar"); },
                      {"unknown planner 'rrtstar'", "biest, bitstar, rrtconnect"});
  EXPECT_STREQ(ToString(PlannerStatus::kInvalidGoal), "invalid_goal");
}

}  // namespace
}  // namespace foresight::manipulation
