// The constraint projection with the real collision cost operator (thesis ch 7): a predicted
// component that runs into a wall is projected onto C <= epsilon; the result meets the constraint
// by an independent Monte Carlo estimate, stays close to the prior, and moves away from the wall.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/matrix_normal.h"
#include "inference/constrained/collision_cost.h"
#include "inference/constrained/kl.h"
#include "inference/constrained/projection.h"
#include "tests/constrained/half_plane_map.h"

namespace foresight::constrained {
namespace {

TEST(ConstrainedProjection, ACollidingComponentIsProjectedOntoTheConstraint) {
  const SmoothHalfPlane wall(Eigen::Vector2d(1, 0), 3.0, 8.0);  // occupied for x > 3 m
  const TimeBasis basis(8, 0.0, 4.8, 1.0);
  const Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(12, 0.2, 4.6);
  const CollisionCost cost(&wall, basis, times, 12);
  // A prior that walks along x at 1 m/s from the origin: it crosses the wall at t = 3 s.
  ComponentParams prior;
  prior.mean = Eigen::MatrixXd::Zero(8, 2);
  for (int j = 0; j < 8; ++j) prior.mean(j, 0) = basis.centres()[j] * 0.9;
  prior.log_u = Eigen::VectorXd::Constant(8, -3.0);
  prior.chol_v << 0.5, 0, 0.1, 0.4;
  CollisionCost::Workspace ws = cost.MakeWorkspace();
  const double prior_cost = cost.Component(prior, &ws, nullptr);
  ASSERT_GT(prior_cost, 0.1);

  const ConstraintFunction c = [&](const ComponentParams& p, ComponentGradient* g) {
    return cost.Component(p, &ws, g);
  };
  ProjectionOptions options;
  options.epsilon = 0.05;
  ComponentParams out;
  const ProjectionSummary s = ProjectComponent(prior, c, options, &out);
  ASSERT_EQ(s.status, ProjectionStatus::kSolved) << s.nlopt_result;
  EXPECT_LE(s.cost, options.epsilon + options.tolerance);
  EXPECT_NEAR(s.prior_cost, prior_cost, 1e-12);
  EXPECT_NEAR(s.kl, MatrixNormalKl(out, prior, nullptr), 1e-9);
  EXPECT_GT(s.kl, 0);

  // Independent check of the constraint: Monte Carlo over sampled trajectories, at the same times.
  MatrixNormal mn;
  mn.mean = out.mean;
  mn.chol_u = out.log_u.array().exp().sqrt().matrix().asDiagonal();
  mn.chol_v = out.chol_v;
  std::mt19937_64 rng(5);
  const int samples = 40000;
  double mc = 0;
  for (int i = 0; i < samples; ++i) {
    const Eigen::MatrixXd w = mn.Sample(&rng);
    for (Eigen::Index k = 0; k < times.size(); ++k) {
      const Eigen::Vector2d x = w.transpose() * basis.Evaluate(times[k]);
      mc += 1 / (1 + std::exp(-8.0 * (x.x() - 3.0)));
    }
  }
  mc /= static_cast<double>(samples) * times.size();
  EXPECT_NEAR(mc, s.cost, 3e-3) << "Monte Carlo " << mc << " vs quadrature " << s.cost;
  // The projected mean stops short of the wall.
  for (Eigen::Index k = 0; k < times.size(); ++k)
    EXPECT_LT((out.mean.transpose() * basis.Evaluate(times[k])).x(), 3.0);
}

}  // namespace
}  // namespace foresight::constrained
