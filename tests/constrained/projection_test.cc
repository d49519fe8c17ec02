// The SLSQP constraint projection on an analytic constraint written here: a half-plane obstacle
// {x : a'x > b} and C(p) = mean_k P(a'x_k > b) = mean_k 1/2 erfc((b - a'mu_k) / sqrt(2 a'Sigma_k
// a)), mu_k = M' phi_k, Sigma_k = (phi_k' U phi_k) V, with its analytic gradient (checked by finite
// differences first). Cases: feasible prior, violating prior (feasibility, optimality against a
// hand-built feasible point, KKT alignment), impossible / NaN / throwing constraints, limits.

#include "inference/constrained/projection.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "inference/constrained/kl.h"
#include "tests/test_util.h"

namespace foresight::constrained {
namespace {

using foresight::testing::ExpectErrorContains;

/// The half-plane collision probability averaged over a few basis vectors phi_k.
struct HalfPlane {
  Eigen::Vector2d a;  // unit normal
  double b = 0;       // offset
  std::vector<Eigen::VectorXd> phis;

  double operator()(const ComponentParams& p, ComponentGradient* g) const {
    const int m = p.basis();
    if (g != nullptr) g->Resize(m);
    const Eigen::Vector2d lta = p.chol_v.transpose() * a;
    const double va = lta.norm();  // sqrt(a' V a)
    const Eigen::VectorXd u = p.log_u.array().exp();
    double c = 0;
    const double k = static_cast<double>(phis.size());
    for (const Eigen::VectorXd& phi : phis) {
      const double s = std::sqrt(phi.dot(u.cwiseProduct(phi)));
      const double sigma = s * va;
      const double z = (b - a.dot(p.mean.transpose() * phi)) / (std::sqrt(2.0) * sigma);
      c += 0.5 * std::erfc(z) / k;
      if (g == nullptr) continue;
      const double dc_dz = -std::exp(-z * z) / std::sqrt(M_PI) / k;
      // z = (b - phi' M a) / (sqrt2 sigma): dz/dM = -phi a' / (sqrt2 sigma), dz/dsigma = -z /
      // sigma.
      g->mean += dc_dz * (-phi * a.transpose() / (std::sqrt(2.0) * sigma));
      const double dc_dsigma = dc_dz * (-z / sigma);
      // sigma = s ||L'a||: ds/dlog_u_j = u_j phi_j^2 / (2 s), d||L'a||/dL = a a' L / ||L'a||.
      g->log_u += dc_dsigma * va * (u.cwiseProduct(phi.cwiseProduct(phi)) / (2 * s));
      Eigen::Matrix2d dl = dc_dsigma * s * (a * a.transpose() * p.chol_v) / va;
      dl(0, 1) = 0;
      g->chol_v += dl;
    }
    return c;
  }
};

ComponentParams MakePrior(int m) {
  ComponentParams p;
  p.mean.resize(m, 2);
  for (int i = 0; i < m; ++i) {
    p.mean(i, 0) = 0.3 * i;
    p.mean(i, 1) = 0.1 * i - 0.2;
  }
  p.log_u = Eigen::VectorXd::LinSpaced(m, -0.5, 0.3);
  p.chol_v << 0.8, 0, 0.2, 0.6;
  return p;
}

HalfPlane MakeHalfPlane(int m, double b) {
  HalfPlane h;
  h.a = Eigen::Vector2d(1.0, 0.5).normalized();
  h.b = b;
  // Gaussian bumps at a few times, like an RBF trajectory basis.
  for (double t : {0.2, 0.5, 0.8}) {
    Eigen::VectorXd phi(m);
    for (int j = 0; j < m; ++j) {
      const double centre = static_cast<double>(j) / (m - 1);
      phi[j] = std::exp(-(t - centre) * (t - centre) / (2 * 0.2 * 0.2));
    }
    h.phis.push_back(phi);
  }
  return h;
}

ConstraintFunction AsFunction(const HalfPlane& h) {
  return [h](const ComponentParams& p, ComponentGradient* g) { return h(p, g); };
}

void ExpectSameComponent(const ComponentParams& x, const ComponentParams& y) {
  EXPECT_EQ(x.mean, y.mean);
  EXPECT_EQ(x.log_u, y.log_u);
  EXPECT_EQ(x.chol_v, y.chol_v);
}

TEST(HalfPlaneConstraint, GradientMatchesCentralDifferences) {
  const int m = 6;
  const ComponentParams p = MakePrior(m);
  const HalfPlane h = MakeHalfPlane(m, 0.8);
  ComponentGradient g;
  const double c = h(p, &g);
  ASSERT_GT(c, 0.05);
  ASSERT_LT(c, 0.95);
  const Eigen::VectorXd grad = g.ToVector(p);
  const Eigen::VectorXd theta = p.ToVector();
  const double step = 1e-6;
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    Eigen::VectorXd x1 = theta;
    Eigen::VectorXd x2 = theta;
    x1[i] += step;
    x2[i] -= step;
    const double num = (h(ComponentParams::FromVector(x1, m), nullptr) -
                        h(ComponentParams::FromVector(x2, m), nullptr)) /
                       (2 * step);
    EXPECT_NEAR(grad[i], num, 1e-7 + 1e-5 * std::abs(num)) << "theta " << i;
  }
}

TEST(ProjectComponent, FeasiblePriorIsReturnedUnchanged) {
  const int m = 5;
  const ComponentParams prior = MakePrior(m);
  const HalfPlane h = MakeHalfPlane(m, 10.0);  // far away
  ComponentParams out;
  const ProjectionSummary s = ProjectComponent(prior, AsFunction(h), ProjectionOptions{}, &out);
  EXPECT_EQ(s.status, ProjectionStatus::kAlreadyFeasible);
  EXPECT_TRUE(s.feasible());
  EXPECT_EQ(s.kl, 0.0);
  EXPECT_EQ(s.evaluations, 0);
  EXPECT_DOUBLE_EQ(s.prior_cost, h(prior, nullptr));
  EXPECT_EQ(s.cost, s.prior_cost);
  ExpectSameComponent(out, prior);
}

/// The prior with its mean moved by -shift * a in every row, shift found by bisection so that the
/// half-plane cost is epsilon: a feasible point that leaves the covariance alone.
ComponentParams ShiftMeanToEpsilon(const ComponentParams& prior, const HalfPlane& h, double eps) {
  double lo = 0;
  double hi = 10;
  const auto shifted = [&](double t) {
    ComponentParams q = prior;
    q.mean.rowwise() -= t * h.a.transpose();
    return q;
  };
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (h(shifted(mid), nullptr) > eps ? lo : hi) = mid;
  }
  return shifted(hi);
}

TEST(ProjectComponent, ViolatingPriorIsProjectedOntoTheConstraint) {
  for (int m : {4, 6, 8}) {
    const ComponentParams prior = MakePrior(m);
    const HalfPlane h = MakeHalfPlane(m, 0.8);
    ProjectionOptions opt;
    opt.max_seconds = 0;  // deterministic: evaluations only
    const double prior_cost = h(prior, nullptr);
    ASSERT_GT(prior_cost, 0.2);
    ComponentParams out;
    const ProjectionSummary s = ProjectComponent(prior, AsFunction(h), opt, &out);
    ASSERT_EQ(s.status, ProjectionStatus::kSolved) << s.nlopt_result;
    EXPECT_TRUE(s.feasible());
    EXPECT_GT(s.evaluations, 0);
    EXPECT_LE(s.evaluations, opt.max_evaluations);
    EXPECT_DOUBLE_EQ(s.prior_cost, prior_cost);
    // Feasible, recomputed independently of the summary.
    const double cost = h(out, nullptr);
    EXPECT_LE(cost, opt.epsilon + opt.tolerance);
    EXPECT_NEAR(cost, s.cost, 1e-12);
    // The constraint is active at the optimum (the prior sits outside).
    EXPECT_GT(cost, opt.epsilon - 1e-3);
    const double kl = MatrixNormalKl(out, prior, nullptr);
    EXPECT_NEAR(kl, s.kl, 1e-12);
    EXPECT_GT(kl, 0.0);
    // No worse than a hand-built feasible point (moving the mean only).
    const ComponentParams shifted = ShiftMeanToEpsilon(prior, h, opt.epsilon);
    const double kl_shift = MatrixNormalKl(shifted, prior, nullptr);
    EXPECT_LE(kl, kl_shift * (1 + 1e-3)) << "m = " << m;
    // KKT: grad KL + lambda grad C = 0 with lambda >= 0, i.e. -grad KL parallel to grad C.
    ComponentGradient gk;
    ComponentGradient gc;
    MatrixNormalKl(out, prior, &gk);
    h(out, &gc);
    const Eigen::VectorXd vk = gk.ToVector(out);
    const Eigen::VectorXd vc = gc.ToVector(out);
    const double cosine = -vk.dot(vc) / (vk.norm() * vc.norm());
    EXPECT_GT(cosine, 0.99) << "m = " << m;
    const double lambda = -vk.dot(vc) / vc.squaredNorm();
    EXPECT_GT(lambda, 0.0);
    EXPECT_LT((vk + lambda * vc).norm(), 0.05 * vk.norm()) << "m = " << m;
  }
}

// A warm start: from a feasible point (the hand-built mean shift) the result is at least as good
// and reaches the cold solve's optimum; from the cold optimum itself it stays there in fewer
// evaluations; an invalid start (NaN) is ignored.
TEST(ProjectComponent, WarmStartIsNeverWorseThanTheStart) {
  const int m = 6;
  const ComponentParams prior = MakePrior(m);
  const HalfPlane h = MakeHalfPlane(m, 0.8);
  ProjectionOptions opt;
  opt.max_seconds = 0;
  ComponentParams cold;
  const ProjectionSummary sc = ProjectComponent(prior, AsFunction(h), opt, &cold);
  ASSERT_EQ(sc.status, ProjectionStatus::kSolved);

  const ComponentParams shifted = ShiftMeanToEpsilon(prior, h, opt.epsilon);
  ComponentParams warm;
  const ProjectionSummary sw = ProjectComponent(prior, AsFunction(h), opt, &warm, shifted);
  ASSERT_EQ(sw.status, ProjectionStatus::kSolved);
  EXPECT_LE(sw.kl, MatrixNormalKl(shifted, prior, nullptr));
  EXPECT_NEAR(sw.kl, sc.kl, 1e-3 * (1 + sc.kl));
  EXPECT_NEAR(sw.kl, MatrixNormalKl(warm, prior, nullptr), 1e-12);  // KL from the prior
  EXPECT_LE(h(warm, nullptr), opt.epsilon + opt.tolerance);

  ComponentParams again;
  const ProjectionSummary sa = ProjectComponent(prior, AsFunction(h), opt, &again, cold);
  ASSERT_EQ(sa.status, ProjectionStatus::kSolved);
  EXPECT_LE(sa.kl, sc.kl * (1 + 1e-9));
  EXPECT_LT(sa.evaluations, sc.evaluations);

  ComponentParams bad = cold;
  bad.mean(0, 0) = std::nan("");
  ComponentParams ignored;
  const ProjectionSummary sb = ProjectComponent(prior, AsFunction(h), opt, &ignored, bad);
  EXPECT_EQ(sb.status, sc.status);
  EXPECT_EQ(sb.evaluations, sc.evaluations);
  EXPECT_DOUBLE_EQ(sb.kl, sc.kl);
}

TEST(ProjectComponent, OutMayAliasThePrior) {
  const int m = 5;
  ComponentParams p = MakePrior(m);
  const ComponentParams prior = p;
  const HalfPlane h = MakeHalfPlane(m, 0.8);
  const ProjectionSummary s = ProjectComponent(p, AsFunction(h), ProjectionOptions{}, &p);
  ASSERT_EQ(s.status, ProjectionStatus::kSolved);
  EXPECT_NEAR(MatrixNormalKl(p, prior, nullptr), s.kl, 1e-12);
}

TEST(ProjectComponent, ImpossibleConstraintDoesNotThrow) {
  const int m = 4;
  const ComponentParams prior = MakePrior(m);
  // C >= 0.2 everywhere: no point meets epsilon = 0.05.
  const ConstraintFunction cost = [](const ComponentParams& p, ComponentGradient* g) {
    const double t = std::tanh(p.mean(0, 0));
    if (g != nullptr) {
      g->Resize(p.basis());
      g->mean(0, 0) = 0.1 * (1 - t * t);
    }
    return 0.2 + 0.1 * (1 + t);
  };
  ProjectionOptions opt;
  opt.max_evaluations = 50;
  ComponentParams out;
  ProjectionSummary s;
  ASSERT_NO_THROW(s = ProjectComponent(prior, cost, opt, &out));
  EXPECT_FALSE(s.feasible());
  ASSERT_TRUE(s.status == ProjectionStatus::kInfeasible || s.status == ProjectionStatus::kFailed)
      << ToString(s.status);
  if (s.status == ProjectionStatus::kFailed) {
    ExpectSameComponent(out, prior);
  } else {
    // The best point found: no costlier than the prior, its summary values its own.
    EXPECT_NEAR(cost(out, nullptr), s.cost, 1e-12);
    EXPECT_LE(s.cost, s.prior_cost);
    EXPECT_NEAR(MatrixNormalKl(out, prior, nullptr), s.kl, 1e-12);
    // SLSQP pushes the saturated tanh ever further (KL ~ 3e4 after 50 evaluations); the point
    // returned is the lowest-KL one within `tolerance` of the lowest cost, far closer to the prior.
    EXPECT_LT(s.cost, 0.2 + 1e-3);
    EXPECT_LT(s.kl, 1e3);
  }
  EXPECT_GT(s.cost, opt.epsilon);
}

TEST(ProjectComponent, NanConstraintFails) {
  const int m = 4;
  const ComponentParams prior = MakePrior(m);
  const HalfPlane h = MakeHalfPlane(m, 0.8);
  ComponentParams out;
  // NaN at the prior already.
  const ConstraintFunction nan_everywhere = [](const ComponentParams&, ComponentGradient* g) {
    if (g != nullptr) g->Resize(4);
    return std::nan("");
  };
  ProjectionSummary s;
  ASSERT_NO_THROW(s = ProjectComponent(prior, nan_everywhere, ProjectionOptions{}, &out));
  EXPECT_EQ(s.status, ProjectionStatus::kFailed);
  EXPECT_TRUE(std::isnan(s.prior_cost));
  ExpectSameComponent(out, prior);
  // Finite at the prior, NaN once the solver moves (in the value or in the gradient).
  for (bool in_gradient : {false, true}) {
    const ConstraintFunction nan_away = [&h, &prior, in_gradient](const ComponentParams& p,
                                                                  ComponentGradient* g) {
      const double c = h(p, g);
      if ((p.mean - prior.mean).norm() == 0) return c;
      if (in_gradient && g != nullptr) {
        g->log_u[0] = std::nan("");
        return c;
      }
      return std::nan("");
    };
    ASSERT_NO_THROW(s = ProjectComponent(prior, nan_away, ProjectionOptions{}, &out));
    EXPECT_EQ(s.status, ProjectionStatus::kFailed) << "in_gradient " << in_gradient;
    EXPECT_EQ(s.nlopt_result, "NLOPT_FORCED_STOP");
    EXPECT_GT(s.evaluations, 0);
    ExpectSameComponent(out, prior);
    EXPECT_EQ(s.kl, 0.0);
    EXPECT_EQ(s.cost, s.prior_cost);
  }
}

TEST(ProjectComponent, ThrowingConstraintFails) {
  const int m = 4;
  const ComponentParams prior = MakePrior(m);
  const HalfPlane h = MakeHalfPlane(m, 0.8);
  ComponentParams out;
  for (int throw_after : {0, 1, 3}) {
    int calls = 0;
    const ConstraintFunction throwing = [&](const ComponentParams& p, ComponentGradient* g) {
      if (calls++ >= throw_after) throw std::runtime_error("occupancy map went away");
      return h(p, g);
    };
    ProjectionSummary s;
    ASSERT_NO_THROW(s = ProjectComponent(prior, throwing, ProjectionOptions{}, &out));
    EXPECT_EQ(s.status, ProjectionStatus::kFailed) << "throw_after " << throw_after;
    ExpectSameComponent(out, prior);
    if (throw_after > 0) {
      EXPECT_EQ(s.nlopt_result, "NLOPT_FORCED_STOP");
    }
  }
}

TEST(ProjectComponent, EvaluationLimitKeepsTheBestPoint) {
  const int m = 6;
  const ComponentParams prior = MakePrior(m);
  const HalfPlane h = MakeHalfPlane(m, 0.8);
  for (int limit : {1, 2, 4}) {
    ProjectionOptions opt;
    opt.max_evaluations = limit;
    ComponentParams out;
    // Each attempt (the first and every restart from the lowest-cost point) has the budget.
    const ProjectionSummary s = ProjectComponent(prior, AsFunction(h), opt, &out);
    // ... and the feasibility phase its samples, L-BFGS's budget and one more SLSQP attempt.
    EXPECT_LE(s.evaluations, (opt.restarts + 3) * limit + opt.feasibility_samples);
    ProjectionOptions once = opt;
    once.restarts = 0;
    once.feasibility_phase = false;
    ComponentParams out_once;
    EXPECT_LE(ProjectComponent(prior, AsFunction(h), once, &out_once).evaluations, limit);
    ASSERT_TRUE(s.status == ProjectionStatus::kSolved || s.status == ProjectionStatus::kInfeasible)
        << ToString(s.status) << " " << s.nlopt_result;
    EXPECT_NEAR(h(out, nullptr), s.cost, 1e-12);
    EXPECT_NEAR(MatrixNormalKl(out, prior, nullptr), s.kl, 1e-12);
    EXPECT_LE(s.cost, s.prior_cost);
    if (s.status == ProjectionStatus::kSolved) {
      EXPECT_LE(s.cost, opt.epsilon + opt.tolerance);
    } else {
      EXPECT_GT(s.cost, opt.epsilon + opt.tolerance);
    }
  }
}

// C has a local minimum at the prior (zero gradient, C = 0.2) and meets epsilon only in a narrow
// well 2 units away along mean(0, 0): SLSQP and its restarts stay at the prior; the feasibility
// phase's prior samples land in the well, and SLSQP then lowers the KL from there.
TEST(ProjectComponent, FeasibilityPhaseLeavesALocalMinimum) {
  const int m = 4;
  ComponentParams prior = MakePrior(m);
  prior.log_u.setConstant(std::log(1.5 * 1.5));
  prior.chol_v.setIdentity();
  const double x0 = prior.mean(0, 0);
  const ConstraintFunction cost = [x0](const ComponentParams& p, ComponentGradient* g) {
    const double x = p.mean(0, 0) - x0;
    const double bump = 0.1 * std::exp(-x * x / 0.5);
    const double well = 0.29 * std::exp(-(x - 2) * (x - 2) / 0.1);
    if (g != nullptr) {
      g->Resize(p.basis());
      g->mean(0, 0) = bump * 2 * x / 0.5 + well * 2 * (x - 2) / 0.1;
    }
    return 0.3 - bump - well;
  };
  ProjectionOptions opt;
  ComponentParams out;
  const ProjectionSummary s = ProjectComponent(prior, cost, opt, &out);
  ASSERT_EQ(s.status, ProjectionStatus::kSolved) << s.nlopt_result;
  EXPECT_LE(s.cost, opt.epsilon + opt.tolerance);
  EXPECT_NEAR(cost(out, nullptr), s.cost, 1e-12);
  EXPECT_NEAR(MatrixNormalKl(out, prior, nullptr), s.kl, 1e-12);
  EXPECT_NEAR(out.mean(0, 0) - x0, 2.0, 0.3);
  // Deterministic (seeded samples).
  ComponentParams again;
  const ProjectionSummary s2 = ProjectComponent(prior, cost, opt, &again);
  EXPECT_EQ(s2.kl, s.kl);
  ExpectSameComponent(again, out);
  // SLSQP without it ends where it started: infeasible, at the prior.
  opt.feasibility_phase = false;
  ComponentParams stuck;
  const ProjectionSummary s3 = ProjectComponent(prior, cost, opt, &stuck);
  EXPECT_EQ(s3.status, ProjectionStatus::kInfeasible);
  EXPECT_NEAR(s3.cost, 0.2, 1e-6);
}

TEST(ProjectComponent, NonFinitePriorFails) {
  const int m = 4;
  ComponentParams prior = MakePrior(m);
  prior.log_u[1] = std::nan("");
  const HalfPlane h = MakeHalfPlane(m, 0.8);
  ComponentParams out;
  ProjectionSummary s;
  ASSERT_NO_THROW(s = ProjectComponent(prior, AsFunction(h), ProjectionOptions{}, &out));
  EXPECT_EQ(s.status, ProjectionStatus::kFailed);
  EXPECT_TRUE(std::isnan(out.log_u[1]));
}

TEST(ProjectComponent, RejectsBadArguments) {
  const int m = 4;
  const ComponentParams prior = MakePrior(m);
  const ConstraintFunction cost = AsFunction(MakeHalfPlane(m, 0.8));
  ComponentParams out;
  ExpectErrorContains([&] { ProjectComponent(prior, cost, ProjectionOptions{}, nullptr); },
                      {"ProjectComponent", "out"});
  ExpectErrorContains([&] { ProjectComponent(prior, ConstraintFunction{}, {}, &out); },
                      {"ProjectComponent", "constraint function"});
  ProjectionOptions opt;
  opt.max_evaluations = 0;
  ExpectErrorContains([&] { ProjectComponent(prior, cost, opt, &out); }, {"max_evaluations", "0"});
  opt = ProjectionOptions{};
  opt.tolerance = -1;
  ExpectErrorContains([&] { ProjectComponent(prior, cost, opt, &out); }, {"tolerance", "-1"});
  opt = ProjectionOptions{};
  opt.epsilon = std::nan("");
  ExpectErrorContains([&] { ProjectComponent(prior, cost, opt, &out); }, {"epsilon", "nan"});
  ComponentParams bad = prior;
  bad.log_u.resize(2);
  ExpectErrorContains([&] { ProjectComponent(bad, cost, {}, &out); }, {"prior.log_u", "2"});
}

TEST(ProjectionStatus, ToStringNamesEveryStatus) {
  EXPECT_STREQ(ToString(ProjectionStatus::kAlreadyFeasible), "already_feasible");
  EXPECT_STREQ(ToString(ProjectionStatus::kSolved), "solved");
  EXPECT_STREQ(ToString(ProjectionStatus::kInfeasible), "infeasible");
  EXPECT_STREQ(ToString(ProjectionStatus::kFailed), "failed");
}

}  // namespace
}  // namespace foresight::constrained
