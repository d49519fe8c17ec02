// The runtime projector (thesis ch 7) on hand-built predicted mixtures: the offset of
// CollisionCost against a shifted map, the parameter conversion, the projection checked by an
// independent Monte Carlo of the mixture (trajectories sampled by TrajectoryDistribution::
// SamplePath, occupancy from the sigmoid formula written here), compliant and impossible priors,
// and the allocation-free Cost.

#include "inference/constrained/distribution_projector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "inference/constrained/kl.h"
#include "tests/constrained/half_plane_map.h"
#include "tests/test_util.h"
#define FORESIGHT_ALLOC_COUNTER_MALLOC  // count Eigen's malloc too
#include "tests/alloc_counter.h"        // replaces operator new: one per binary

namespace foresight::constrained {
namespace {

using foresight::testing::ExpectErrorContains;

// p = 0.9 everywhere: no distribution can meet C <= 0.05.
class FullyOccupied final : public occupancy::Map {
 public:
  std::string model_type() const override { return "test.fully_occupied"; }
  occupancy::MapWorkspace MakeWorkspace() const override { return {}; }
  occupancy::QueryResult Query(double, double, occupancy::MapWorkspace*) const override {
    occupancy::QueryResult q;
    q.probability = 0.9;
    return q;
  }
  Eigen::Vector4d Extent() const override { return {-1e3, 1e3, -1e3, 1e3}; }
};

constexpr double kDt = 0.4;
constexpr int kSteps = 12;
// The wall: p = sigmoid(kSharp (x - kWall)), occupied for x > 3 m.
constexpr double kWall = 3.0;
constexpr double kSharp = 8.0;

TimeBasis Basis() { return TimeBasis(8, 0.0, 4.8, 1.0); }
Eigen::VectorXd Times() { return Eigen::VectorXd::LinSpaced(kSteps, kDt, kSteps * kDt); }
SmoothHalfPlane Wall() { return SmoothHalfPlane(Eigen::Vector2d(1, 0), kWall, kSharp); }

/// Weights of the residual path t -> rate t (straight line from the origin of the frame).
Eigen::MatrixXd ResidualMean(const TimeBasis& basis, const Eigen::Vector2d& rate) {
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(25, 0.0, 4.8);
  Eigen::MatrixXd points(25, 2);
  for (int i = 0; i < 25; ++i) points.row(i) = (rate * t[i]).transpose();
  return basis.FitRidge(t, points, 1e-3);
}

/// Two components on the frame origin (0, 0) + (0.5, 0) t: component 0 drifts further in x and
/// crosses the wall (x reaches ~3.8 m); component 1 turns away in y and stays near x <= 2.4 m.
TrajectoryDistribution TwoComponents(double x_drift = 0.3) {
  const TimeBasis basis = Basis();
  TrajectoryDistribution d(basis, 2);
  d.SetFrame(Eigen::Vector2d(0, 0), Eigen::Vector2d(0.5, 0), Eigen::Vector2d(0.6, 0.4));
  Eigen::MatrixXd lu0 = Eigen::VectorXd::LinSpaced(basis.size(), -3.2, -2.6)
                            .array()
                            .exp()
                            .sqrt()
                            .matrix()
                            .asDiagonal();
  Eigen::MatrixXd lu1 = (0.9 * lu0).eval();
  Eigen::Matrix2d lv0, lv1;
  lv0 << 0.6, 0, 0.1, 0.5;
  lv1 << 0.5, 0, -0.05, 0.6;
  d.SetComponent(0, ResidualMean(basis, Eigen::Vector2d(x_drift, 0.05)), lu0, lv0);
  d.SetComponent(1, ResidualMean(basis, Eigen::Vector2d(-0.1, -0.5)), lu1, lv1);
  return d;
}

/// Monte Carlo of the mixture's C = E[1/K sum_k p(o(t_k))] over sampled trajectories.
struct McEstimate {
  double mean = 0, sigma = 0;
};
McEstimate MonteCarloCost(const TrajectoryDistribution& d, const SmoothHalfPlane& map, int n,
                          std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const Eigen::VectorXd times = Times();
  Eigen::Matrix<double, Eigen::Dynamic, 2> path(times.size(), 2);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    d.SamplePath(times, &rng, path);
    double c = 0;
    for (Eigen::Index k = 0; k < times.size(); ++k) {
      c += 1 / (1 + std::exp(-kSharp * (path(k, 0) - kWall)));
    }
    c /= static_cast<double>(times.size());
    sum += c;
    sum2 += c * c;
  }
  McEstimate e;
  e.mean = sum / n;
  e.sigma = std::sqrt(std::max(0.0, sum2 / n - e.mean * e.mean) / n);
  return e;
}

void ExpectSameDistribution(const TrajectoryDistribution& x, const TrajectoryDistribution& y) {
  ASSERT_EQ(x.components(), y.components());
  EXPECT_EQ(x.origin(), y.origin());
  EXPECT_EQ(x.velocity(), y.velocity());
  for (int r = 0; r < x.components(); ++r) {
    EXPECT_EQ(x.alpha(r), y.alpha(r));
    EXPECT_EQ(x.mean(r), y.mean(r)) << "component " << r;
    EXPECT_EQ(x.chol_u(r), y.chol_u(r)) << "component " << r;
    EXPECT_EQ(x.chol_v(r), y.chol_v(r)) << "component " << r;
  }
}

/// Projects a copy of `prior` with `projector` (a workspace of its own).
struct Projected {
  TrackProjection result;
  TrajectoryDistribution out;
};
Projected ProjectCopy(const DistributionProjector& projector, const TrajectoryDistribution& prior) {
  auto ws = projector.MakeWorkspace();
  Projected p{TrackProjection{}, prior};
  p.result = projector.Project(prior, &p.out, &ws);
  return p;
}

// ---------------------------------------------------------------- CollisionCost offset

TEST(CollisionCostOffset, EqualsShiftingTheMap) {
  const TimeBasis basis = Basis();
  const Eigen::VectorXd times = Times();
  const Eigen::Vector2d a = Eigen::Vector2d(0.6, 0.8);
  const double b = 1.0;
  const SmoothHalfPlane map(a, b, 3.0);
  const CollisionCost cost(&map, basis, times, 6);
  const TrajectoryDistribution d = TwoComponents();
  const ComponentParams c = ToComponentParams(d, 0);
  // o_k = shift + t_k w with a'w = 0: moving along the wall, so p(x + o_k) is the map shifted by
  // a'shift: sigmoid(k (a'x - (b - a'shift))).
  const Eigen::Vector2d shift(0.7, -0.3);
  const Eigen::Vector2d w(-0.8, 0.6);
  CollisionCost::Workspace ws = cost.MakeWorkspace();
  ws.offset.resize(2, times.size());
  for (Eigen::Index k = 0; k < times.size(); ++k) ws.offset.col(k) = shift + times[k] * w;
  ComponentGradient g_offset;
  const double with_offset = cost.Component(c, &ws, &g_offset);

  const SmoothHalfPlane shifted(a, b - a.dot(shift), 3.0);
  const CollisionCost cost_shifted(&shifted, basis, times, 6);
  CollisionCost::Workspace ws_shifted = cost_shifted.MakeWorkspace();
  ComponentGradient g_shifted;
  const double with_map = cost_shifted.Component(c, &ws_shifted, &g_shifted);
  ASSERT_GT(with_map, 0.05);
  EXPECT_NEAR(with_offset, with_map, 1e-12);
  EXPECT_LT((g_offset.mean - g_shifted.mean).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((g_offset.log_u - g_shifted.log_u).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((g_offset.chol_v - g_shifted.chol_v).cwiseAbs().maxCoeff(), 1e-12);
  // The offset changes the value on the original map; an empty offset is zero.
  CollisionCost::Workspace ws_zero = cost.MakeWorkspace();
  EXPECT_GT(std::abs(cost.Component(c, &ws_zero, nullptr) - with_offset), 1e-3);
  // Mixture uses it too.
  const std::vector<ComponentParams> comps = {c, ToComponentParams(d, 1)};
  const double mix = cost.Mixture({0.3, 0.7}, comps, &ws);
  EXPECT_NEAR(mix, 0.3 * with_offset + 0.7 * cost_shifted.Component(comps[1], &ws_shifted, nullptr),
              1e-12);
  // Abscissae: the same points moved by o_k.
  const Eigen::Matrix2Xd plain = cost.Abscissae(c);
  const Eigen::Matrix2Xd moved = cost.Abscissae(c, ws.offset);
  const int nq = cost.order() * cost.order();
  for (Eigen::Index k = 0; k < times.size(); ++k) {
    const Eigen::Matrix2Xd diff = moved.middleCols(k * nq, nq) - plain.middleCols(k * nq, nq);
    EXPECT_LT((diff.colwise() - ws.offset.col(k)).cwiseAbs().maxCoeff(), 1e-12);
  }
  // A wrong-sized offset names itself.
  ws.offset.resize(2, 3);
  ExpectErrorContains([&] { cost.Component(c, &ws, nullptr); }, {"offset", "2 x 3", "12"});
  ExpectErrorContains([&] { cost.Abscissae(c, ws.offset); }, {"offset"});
}

// ---------------------------------------------------------------- conversion

TEST(ComponentConversion, RoundTripsAndChecksDiagonalU) {
  const TrajectoryDistribution d = TwoComponents();
  for (int r = 0; r < 2; ++r) {
    const ComponentParams p = ToComponentParams(d, r);
    EXPECT_EQ(p.mean, d.mean(r));
    EXPECT_EQ(p.chol_v, d.chol_v(r));
    for (int i = 0; i < d.basis_size(); ++i) {
      // U = L_U L_U' = diag(L_U(i,i)^2).
      EXPECT_NEAR(std::exp(p.log_u[i]), d.chol_u(r)(i, i) * d.chol_u(r)(i, i), 1e-15);
    }
    TrajectoryDistribution e(Basis(), 2);
    SetFromComponentParams(p, r, &e);
    EXPECT_EQ(e.mean(r), d.mean(r));
    EXPECT_EQ(e.chol_v(r), d.chol_v(r));
    EXPECT_LT((e.chol_u(r) - d.chol_u(r)).cwiseAbs().maxCoeff(), 1e-15);
  }
  TrajectoryDistribution full = TwoComponents();
  Eigen::MatrixXd lu = full.chol_u(1);
  lu(3, 1) = 0.01;
  full.SetComponent(1, full.mean(1), lu, full.chol_v(1));
  ExpectErrorContains([&] { ToComponentParams(full, 1); }, {"u_param: diagonal", "L_U(3, 1)"});
  ExpectErrorContains([&] { ToComponentParams(full, 2); }, {"component 2", "out of range"});
  ComponentParams small = ToComponentParams(d, 0);
  small.mean.conservativeResize(5, 2);
  small.log_u.conservativeResize(5);
  TrajectoryDistribution e(Basis(), 2);
  ExpectErrorContains([&] { SetFromComponentParams(small, 0, &e); }, {"basis 5", "basis 8"});
}

TEST(TrajectoryDistributionSetters, RejectShapeMismatch) {
  TrajectoryDistribution d(Basis(), 2);
  const Eigen::Matrix2d lv = Eigen::Matrix2d::Identity();
  ExpectErrorContains(
      [&] { d.SetComponent(0, Eigen::MatrixXd::Zero(7, 2), Eigen::MatrixXd::Zero(8, 8), lv); },
      {"mean is 7 x 2", "8 x 2"});
  ExpectErrorContains(
      [&] { d.SetComponent(1, Eigen::MatrixXd::Zero(8, 2), Eigen::MatrixXd::Zero(8, 3), lv); },
      {"chol_u is 8 x 3", "8 x 8"});
  ExpectErrorContains(
      [&] { d.SetComponent(2, Eigen::MatrixXd::Zero(8, 2), Eigen::MatrixXd::Zero(8, 8), lv); },
      {"component 2", "[0, 2)"});
  ExpectErrorContains(
      [&] {
        d.SetFrame({0, 0}, {0, 0}, Eigen::VectorXd::Ones(3));
      },
      {"alpha has 3", "2 components"});
  // Position() reflects the setters: origin + v t + M' phi(t).
  const TrajectoryDistribution e = TwoComponents();
  Eigen::Vector2d mu;
  Eigen::Matrix2d cov;
  e.Position(2.0, 0, &mu, &cov);
  const Eigen::Vector2d expected = Eigen::Vector2d(0, 0) + 2.0 * Eigen::Vector2d(0.5, 0) +
                                   e.mean(0).transpose() * Basis().Evaluate(2.0);
  EXPECT_LT((mu - expected).norm(), 1e-12);
}

// ---------------------------------------------------------------- projection

TEST(DistributionProjector, ProjectsTheCrossingComponentOnly) {
  const SmoothHalfPlane map = Wall();
  ProjectorOptions options;
  options.solver.max_seconds = 0;  // deterministic: evaluations only
  const DistributionProjector projector(&map, Basis(), Times(), options);
  auto ws = projector.MakeWorkspace();
  const TrajectoryDistribution prior = TwoComponents();
  // The cost with the frame's offset agrees with an independent Monte Carlo of the prior.
  const double prior_cost = projector.Cost(prior, &ws);
  const McEstimate mc_prior = MonteCarloCost(prior, map, 200000, 11);
  EXPECT_NEAR(prior_cost, mc_prior.mean, 3 * mc_prior.sigma + 1e-3);
  ASSERT_GT(prior_cost, 0.1);
  ASSERT_LT(projector.cost().Component(ToComponentParams(prior, 1), &ws.cost, nullptr),
            options.epsilon - options.margin);

  TrajectoryDistribution out = prior;
  const TrackProjection r = projector.Project(prior, &out, &ws);
  ASSERT_EQ(r.status, "solved") << ToString(r.components[0].status) << " "
                                << r.components[0].nlopt_result;
  EXPECT_TRUE(r.changed);
  EXPECT_TRUE(r.feasible);
  EXPECT_DOUBLE_EQ(r.prior_cost, prior_cost);
  EXPECT_LE(r.cost, options.epsilon);
  EXPECT_NEAR(r.cost, projector.Cost(out, &ws), 1e-12);
  ASSERT_EQ(r.components.size(), 2u);
  EXPECT_EQ(r.components[0].status, ProjectionStatus::kSolved);
  EXPECT_EQ(r.components[1].status, ProjectionStatus::kAlreadyFeasible);
  EXPECT_GT(r.evaluations, 0);
  EXPECT_GE(r.seconds, 0.0);
  // The compliant component and the frame are untouched.
  EXPECT_EQ(out.mean(1), prior.mean(1));
  EXPECT_EQ(out.chol_u(1), prior.chol_u(1));
  EXPECT_EQ(out.chol_v(1), prior.chol_v(1));
  EXPECT_EQ(out.origin(), prior.origin());
  EXPECT_EQ(out.velocity(), prior.velocity());
  EXPECT_EQ(out.alpha(0), prior.alpha(0));
  // KL: alpha-weighted, recomputed from the distributions.
  const double kl0 =
      MatrixNormalKl(ToComponentParams(out, 0), ToComponentParams(prior, 0), nullptr);
  EXPECT_GT(r.kl, 0.0);
  EXPECT_NEAR(r.kl, prior.alpha(0) * kl0, 1e-9 * (1 + kl0));
  // Independent check of compliance: Monte Carlo of the returned mixture.
  const McEstimate mc = MonteCarloCost(out, map, 200000, 12);
  EXPECT_LE(mc.mean, options.epsilon + 3 * mc.sigma) << "MC " << mc.mean << " +- " << mc.sigma;
  EXPECT_LT(mc.mean, mc_prior.mean - 0.05);
}

TEST(DistributionProjector, CompliantPriorIsReturnedUnchanged) {
  const SmoothHalfPlane map = Wall();
  const DistributionProjector projector(&map, Basis(), Times(), ProjectorOptions{});
  auto ws = projector.MakeWorkspace();
  const TrajectoryDistribution prior = TwoComponents(/*x_drift=*/-0.3);  // stays left of the wall
  TrajectoryDistribution out = TwoComponents(0.5);                       // same shape, other values
  const TrackProjection r = projector.Project(prior, &out, &ws);
  EXPECT_FALSE(r.changed);
  EXPECT_TRUE(r.feasible);
  EXPECT_EQ(r.status, "compliant_prior");
  EXPECT_EQ(r.kl, 0.0);
  EXPECT_EQ(r.evaluations, 0);
  EXPECT_LE(r.prior_cost, 0.05);
  EXPECT_EQ(r.cost, r.prior_cost);
  ExpectSameDistribution(out, prior);
  for (const ProjectionSummary& s : r.components) {
    EXPECT_EQ(s.status, ProjectionStatus::kAlreadyFeasible);
  }
}

TEST(DistributionProjector, OutMayBeThePrior) {
  const SmoothHalfPlane map = Wall();
  ProjectorOptions options;
  options.solver.max_seconds = 0;  // deterministic: evaluations only
  const DistributionProjector projector(&map, Basis(), Times(), options);
  auto ws = projector.MakeWorkspace();
  const TrajectoryDistribution prior = TwoComponents();
  TrajectoryDistribution d = prior;
  const TrackProjection r = projector.Project(d, &d, &ws);
  EXPECT_EQ(r.status, "solved");
  EXPECT_NEAR(r.cost, projector.Cost(d, &ws), 1e-12);
  EXPECT_NEAR(r.kl,
              prior.alpha(0) *
                  MatrixNormalKl(ToComponentParams(d, 0), ToComponentParams(prior, 0), nullptr),
              1e-9);
}

TEST(DistributionProjector, ImpossibleConstraintIsReportedNotThrown) {
  const FullyOccupied map;
  ProjectorOptions options;
  options.solver.max_evaluations = 40;
  const DistributionProjector projector(&map, Basis(), Times(), options);
  auto ws = projector.MakeWorkspace();
  const TrajectoryDistribution prior = TwoComponents();
  TrajectoryDistribution out = prior;
  TrackProjection r;
  ASSERT_NO_THROW(r = projector.Project(prior, &out, &ws));
  EXPECT_FALSE(r.feasible);
  EXPECT_TRUE(r.status == "infeasible" || r.status == "failed") << r.status;
  EXPECT_TRUE(r.changed);
  EXPECT_NEAR(r.prior_cost, 0.9, 1e-9);
  EXPECT_GT(r.cost, options.epsilon);
  EXPECT_NEAR(r.cost, projector.Cost(out, &ws), 1e-12);
  for (const ProjectionSummary& s : r.components) EXPECT_FALSE(s.feasible());
}

// The solver drives the configured operator down and so seeks out its quadrature error: with a
// crude one-point rule (C from the mean alone) on a sharp wall, the plain projection's result
// violates under an accurate
// order-20 operator (built here, apart from the projector). With that operator as the check, the
// projector solves again with a lowered target until the accurate C meets epsilon too.
TEST(DistributionProjector, CheckOperatorCatchesTheErrorTheSolverExploits) {
  const SmoothHalfPlane map(Eigen::Vector2d(1, 0), kWall, 40.0);
  ProjectorOptions options;
  options.order = 1;
  options.margin = 0.002;
  options.solver.max_seconds = 0;  // deterministic: evaluations only
  ProjectorOptions accurate_options;
  accurate_options.order = 20;
  const DistributionProjector accurate(&map, Basis(), Times(), accurate_options);
  auto aws = accurate.MakeWorkspace();
  const TrajectoryDistribution prior = TwoComponents(1.0);

  const Projected plain =
      ProjectCopy(DistributionProjector(&map, Basis(), Times(), options), prior);
  const TrackProjection& p = plain.result;
  ASSERT_TRUE(p.feasible) << p.status;
  EXPECT_TRUE(std::isnan(p.checked_cost));
  ASSERT_GT(accurate.Cost(plain.out, &aws), options.epsilon)
      << "the case must exploit the crude rule";

  options.check_order = 20;
  const Projected checked =
      ProjectCopy(DistributionProjector(&map, Basis(), Times(), options, Times()), prior);
  const TrackProjection& r = checked.result;
  ASSERT_TRUE(r.feasible) << r.status << " checked C " << r.checked_cost;
  EXPECT_EQ(r.status, "solved");
  EXPECT_GE(r.check_rounds, 1);
  EXPECT_LE(r.cost, options.epsilon);
  EXPECT_LE(r.checked_cost, options.epsilon);
  EXPECT_NEAR(r.checked_cost, accurate.Cost(checked.out, &aws), 1e-12);

  // With a slack the check accepts only C_check <= epsilon - slack; a slack of the margin or more
  // is refused.
  ProjectorOptions slack = options;
  slack.check_slack = 0.0015;
  const TrackProjection k =
      ProjectCopy(DistributionProjector(&map, Basis(), Times(), slack, Times()), prior).result;
  ASSERT_TRUE(k.feasible) << k.status << " checked C " << k.checked_cost;
  EXPECT_LE(k.checked_cost, options.epsilon - slack.check_slack);
  slack.check_slack = options.margin;
  ExpectErrorContains([&] { DistributionProjector(&map, Basis(), Times(), slack, Times()); },
                      {"DistributionProjector", "check_slack"});

  // No repeated solve allowed: the same failing check makes the result infeasible, not compliant.
  options.check_rounds = 0;
  const TrackProjection s =
      ProjectCopy(DistributionProjector(&map, Basis(), Times(), options, Times()), prior).result;
  EXPECT_FALSE(s.feasible);
  EXPECT_EQ(s.status, "infeasible");
  EXPECT_GT(s.checked_cost, options.epsilon);

  options.check_order = 0;
  ExpectErrorContains([&] { DistributionProjector(&map, Basis(), Times(), options, Times()); },
                      {"DistributionProjector", "check_order"});
}

// A prior the crude rule calls compliant (its mean stays left of the wall) while its spread puts
// mass beyond it: the check rejects it, and the repeated solve against the check operator itself
// makes it compliant. Also with out == &prior.
TEST(DistributionProjector, CheckRejectsAPriorTheCrudeRuleCallsCompliant) {
  const SmoothHalfPlane map(Eigen::Vector2d(1, 0), kWall, 40.0);
  ProjectorOptions options;
  options.order = 1;
  options.solver.max_seconds = 0;
  const DistributionProjector plain(&map, Basis(), Times(), options);
  auto pws = plain.MakeWorkspace();
  options.check_order = 20;
  const DistributionProjector checked(&map, Basis(), Times(), options, Times());
  auto cws = checked.MakeWorkspace();
  ExpectErrorContains([&] { DistributionProjector(&map, Basis(), Times(), options); },
                      {"DistributionProjector", "check_order 20", "check_times"});
  ProjectorOptions accurate_options;
  accurate_options.order = 20;
  const DistributionProjector accurate(&map, Basis(), Times(), accurate_options);
  auto aws = accurate.MakeWorkspace();

  // Component 0 of TwoComponents ending 0.1 m short of the wall, with 3x the spread.
  TrajectoryDistribution prior = TwoComponents(/*x_drift=*/0.12);
  prior.SetComponent(0, prior.mean(0), 3 * prior.chol_u(0), prior.chol_v(0));
  ASSERT_LE(plain.Cost(prior, &pws), options.epsilon);
  ASSERT_GT(accurate.Cost(prior, &aws), options.epsilon) << "the prior must fool the crude rule";
  TrajectoryDistribution p_out = prior;
  const TrackProjection p = plain.Project(prior, &p_out, &pws);
  EXPECT_EQ(p.status, "compliant_prior");

  for (const bool alias : {false, true}) {
    TrajectoryDistribution d = prior;
    TrajectoryDistribution other = prior;
    TrajectoryDistribution* out = alias ? &d : &other;
    const TrackProjection r = checked.Project(d, out, &cws);
    ASSERT_TRUE(r.feasible) << r.status << " checked C " << r.checked_cost << " alias " << alias;
    EXPECT_EQ(r.status, "solved");
    EXPECT_TRUE(r.changed);
    EXPECT_EQ(r.check_rounds, 1);
    EXPECT_GT(r.evaluations, 0);
    EXPECT_LE(r.checked_cost, options.epsilon);
    EXPECT_NEAR(r.checked_cost, accurate.Cost(*out, &aws), 1e-12);
    EXPECT_NEAR(r.cost, plain.Cost(*out, &pws), 1e-12);  // `cost` stays the configured operator's
    EXPECT_NEAR(r.prior_cost, plain.Cost(prior, &pws), 1e-12);  // and so does `prior_cost`
  }
}

TEST(DistributionProjector, NonFinitePriorFails) {
  const SmoothHalfPlane map = Wall();
  const DistributionProjector projector(&map, Basis(), Times(), ProjectorOptions{});
  auto ws = projector.MakeWorkspace();
  TrajectoryDistribution prior = TwoComponents();
  Eigen::MatrixXd mean = prior.mean(0);
  mean(2, 0) = std::nan("");
  prior.SetComponent(0, mean, prior.chol_u(0), prior.chol_v(0));
  TrajectoryDistribution out = prior;
  TrackProjection r;
  ASSERT_NO_THROW(r = projector.Project(prior, &out, &ws));
  EXPECT_EQ(r.status, "failed");
  EXPECT_FALSE(r.feasible);
}

TEST(DistributionProjector, RejectsMisuse) {
  const SmoothHalfPlane map = Wall();
  ProjectorOptions bad;
  bad.margin = 0.06;
  ExpectErrorContains([&] { DistributionProjector(&map, Basis(), Times(), bad); },
                      {"margin", "0.06"});
  bad = ProjectorOptions{};
  bad.epsilon = 0;
  ExpectErrorContains([&] { DistributionProjector(&map, Basis(), Times(), bad); },
                      {"epsilon", "0"});
  bad = ProjectorOptions{};
  bad.order = 0;
  ExpectErrorContains([&] { DistributionProjector(&map, Basis(), Times(), bad); }, {"order", "0"});
  bad = ProjectorOptions{};
  bad.solver.max_evaluations = 0;
  ExpectErrorContains([&] { DistributionProjector(&map, Basis(), Times(), bad); },
                      {"max_evaluations", "0"});

  const DistributionProjector projector(&map, Basis(), Times(), ProjectorOptions{});
  auto ws = projector.MakeWorkspace();
  const TrajectoryDistribution prior = TwoComponents();
  TrajectoryDistribution one(Basis(), 1);
  ExpectErrorContains([&] { projector.Project(prior, &one, &ws); },
                      {"out has 1 components", "prior 2"});
  TrajectoryDistribution other_basis(TimeBasis(5, 0.0, 4.8, 1.0), 2);
  TrajectoryDistribution other_out = other_basis;
  ExpectErrorContains([&] { projector.Project(other_basis, &other_out, &ws); },
                      {"5 basis functions", "8"});
  TrajectoryDistribution full = prior;
  Eigen::MatrixXd lu = full.chol_u(0);
  lu(1, 0) = 0.1;
  full.SetComponent(0, full.mean(0), lu, full.chol_v(0));
  TrajectoryDistribution out = full;
  ExpectErrorContains([&] { projector.Project(full, &out, &ws); }, {"u_param: diagonal"});
}

TEST(DistributionProjector, CostAllocatesNothing) {
#ifndef FORESIGHT_COUNTS_MALLOC
  GTEST_SKIP() << "malloc is not counted in this build (neither glibc nor AddressSanitizer); "
                  "operator new only";
#endif
  const SmoothHalfPlane map = Wall();
  const DistributionProjector projector(&map, Basis(), Times(), ProjectorOptions{});
  auto ws = projector.MakeWorkspace();
  const TrajectoryDistribution d = TwoComponents();
  const TrajectoryDistribution e = TwoComponents(-0.3);
  double sink = projector.Cost(d, &ws);
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < 3; ++i) {
    sink += projector.Cost(d, &ws);
    sink += projector.Cost(e, &ws);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace foresight::constrained
