#include "inference/constrained/projection.h"

#include <nlopt.h>

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "core/error.h"
#include "inference/constrained/kl.h"

namespace foresight::constrained {

const char* ToString(ProjectionStatus s) {
  switch (s) {
    case ProjectionStatus::kAlreadyFeasible:
      return "already_feasible";
    case ProjectionStatus::kSolved:
      return "solved";
    case ProjectionStatus::kInfeasible:
      return "infeasible";
    case ProjectionStatus::kFailed:
      return "failed";
  }
  return "unknown";
}

namespace {

// NLopt's own nlopt_result_to_string drops the "NLOPT_" prefix the summary documents.
const char* ResultName(nlopt_result r) {
  switch (r) {
    case NLOPT_FAILURE:
      return "NLOPT_FAILURE";
    case NLOPT_INVALID_ARGS:
      return "NLOPT_INVALID_ARGS";
    case NLOPT_OUT_OF_MEMORY:
      return "NLOPT_OUT_OF_MEMORY";
    case NLOPT_ROUNDOFF_LIMITED:
      return "NLOPT_ROUNDOFF_LIMITED";
    case NLOPT_FORCED_STOP:
      return "NLOPT_FORCED_STOP";
    case NLOPT_SUCCESS:
      return "NLOPT_SUCCESS";
    case NLOPT_STOPVAL_REACHED:
      return "NLOPT_STOPVAL_REACHED";
    case NLOPT_FTOL_REACHED:
      return "NLOPT_FTOL_REACHED";
    case NLOPT_XTOL_REACHED:
      return "NLOPT_XTOL_REACHED";
    case NLOPT_MAXEVAL_REACHED:
      return "NLOPT_MAXEVAL_REACHED";
    case NLOPT_MAXTIME_REACHED:
      return "NLOPT_MAXTIME_REACHED";
    default:
      return "NLOPT_UNKNOWN_RESULT";
  }
}

bool AllFinite(const ComponentParams& c) {
  return c.mean.allFinite() && c.log_u.allFinite() && c.chol_v.allFinite();
}

/// State shared by the NLopt callbacks. KL and C are evaluated together at each new point (SLSQP
/// asks for the objective and then the constraint at the same x), so every point visited can be
/// judged for the best-so-far bookkeeping.
struct Problem {
  const ComponentParams* prior = nullptr;
  const ConstraintFunction* cost = nullptr;
  nlopt_opt opt = nullptr;
  int basis = 0;
  double epsilon = 0;
  double feasible_limit = 0;  // epsilon + tolerance

  // Cache of the last point evaluated.
  bool cached = false;
  Eigen::VectorXd x;
  double kl = 0;
  double c = 0;
  Eigen::VectorXd kl_grad;
  Eigen::VectorXd c_grad;
  ComponentGradient work;

  int evaluations = 0;
  bool failed = false;

  // Lowest-KL point meeting C <= epsilon + tolerance.
  bool have_feasible = false;
  Eigen::VectorXd best_feasible;
  double best_feasible_kl = std::numeric_limits<double>::infinity();
  double best_feasible_cost = 0;
  // Returned on kInfeasible: the lowest-KL point among those whose C is within `tolerance` of the
  // lowest C seen (the prior at the start), so that a flat constraint does not drag it far away.
  double tolerance = 0;
  struct Fallback {
    double min_cost = 0;  // lowest C seen
    bool moved = false;   // x is not the prior
    Eigen::VectorXd x;
    double cost = 0, kl = 0;
  } fallback;
};

/// Evaluates KL and C (with gradients) at x unless cached. False after a failure (exception or a
/// non-finite value), which also stops NLopt: its C API cannot carry exceptions.
bool Evaluate(Problem* pb, const double* x, unsigned n) {
  if (pb->failed) return false;
  const Eigen::Map<const Eigen::VectorXd> xv(x, n);
  if (pb->cached && pb->x == xv) return true;
  try {
    pb->x = xv;
    pb->cached = false;
    const ComponentParams p = ComponentParams::FromVector(pb->x, pb->basis);
    pb->kl = MatrixNormalKl(p, *pb->prior, &pb->work);
    pb->kl_grad = pb->work.ToVector(p);
    pb->work.Resize(pb->basis);
    pb->c = (*pb->cost)(p, &pb->work);
    pb->c_grad = pb->work.ToVector(p);
    if (!std::isfinite(pb->kl) || !std::isfinite(pb->c) || !pb->kl_grad.allFinite() ||
        !pb->c_grad.allFinite()) {
      pb->failed = true;
    }
  } catch (...) {  // foresight::Error, std::exception or anything else the constraint throws
    pb->failed = true;
  }
  if (pb->failed) {
    nlopt_force_stop(pb->opt);
    return false;
  }
  pb->cached = true;
  if (pb->c <= pb->feasible_limit && pb->kl < pb->best_feasible_kl) {
    pb->have_feasible = true;
    pb->best_feasible = pb->x;
    pb->best_feasible_kl = pb->kl;
    pb->best_feasible_cost = pb->c;
  }
  pb->fallback.min_cost = std::min(pb->fallback.min_cost, pb->c);
  const bool fallback_stale = pb->fallback.cost > pb->fallback.min_cost + pb->tolerance;
  if (pb->c <= pb->fallback.min_cost + pb->tolerance &&
      (fallback_stale || pb->kl < pb->fallback.kl)) {
    pb->fallback.moved = true;
    pb->fallback.x = pb->x;
    pb->fallback.cost = pb->c;
    pb->fallback.kl = pb->kl;
  }
  return true;
}

/// The NLopt callbacks, one per value of the evaluated point: the KL (SLSQP's objective, counted
/// as an evaluation), C - epsilon (its constraint) and C (the feasibility phase's objective).
enum class Value { kKl, kConstraint, kCost };

template <Value kValue>
double Callback(unsigned n, const double* x, double* grad, void* data) {
  auto* pb = static_cast<Problem*>(data);
  if (kValue != Value::kConstraint) ++pb->evaluations;
  if (!Evaluate(pb, x, n)) {
    if (grad != nullptr) Eigen::Map<Eigen::VectorXd>(grad, n).setZero();
    return HUGE_VAL;
  }
  const bool kl = kValue == Value::kKl;
  if (grad != nullptr) Eigen::Map<Eigen::VectorXd>(grad, n) = kl ? pb->kl_grad : pb->c_grad;
  if (kl) return pb->kl;
  return kValue == Value::kConstraint ? pb->c - pb->epsilon : pb->c;
}

struct OptDeleter {
  void operator()(nlopt_opt o) const { nlopt_destroy(o); }
};

/// Phase I of a projection (ProjectionOptions::feasibility_phase), run when SLSQP and its restarts
/// found no feasible point: SLSQP's linearised steps cannot cross a wall the prior's mean runs
/// into, while a sample of the prior may pass beside it. So weight samples W ~ MN(M, U, V) of the
/// prior, as means with U shrunk, are evaluated first; when none meets the constraint, L-BFGS
/// minimises C alone from the lowest-C point until C <= epsilon - tolerance. Every point goes
/// through pb's bookkeeping. When none is feasible, the points of this phase are forgotten (an
/// infeasible projection returns what SLSQP found, near the prior, not this phase's lowest C).
/// True when a feasible point was found (pb->best_feasible).
bool SeekFeasiblePoint(Problem* pb, const ComponentParams& prior, const Eigen::VectorXd& lower,
                       const Eigen::VectorXd& upper, const ProjectionOptions& options,
                       double seconds_left) {
  const auto start = std::chrono::steady_clock::now();
  const auto out_of_time = [&] {
    return seconds_left > 0 &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >=
               seconds_left;
  };
  const unsigned n = static_cast<unsigned>(lower.size());
  const int m = prior.basis();
  const Problem::Fallback fallback = pb->fallback;

  std::unique_ptr<nlopt_opt_s, OptDeleter> lbfgs(nlopt_create(NLOPT_LD_LBFGS, n));
  if (!lbfgs) return false;
  pb->opt = lbfgs.get();  // a failing callback stops this optimiser
  std::mt19937_64 rng(options.feasibility_seed);
  std::normal_distribution<double> normal;
  const Eigen::VectorXd sd = prior.log_u.array().exp().sqrt();
  ComponentParams sample = prior;
  sample.log_u.array() -= options.feasibility_shrink;
  Eigen::MatrixXd z(m, 2);
  for (int k = 0; k < options.feasibility_samples && !pb->failed && !out_of_time(); ++k) {
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < 2; ++j) z(i, j) = normal(rng);
    sample.mean = prior.mean + sd.asDiagonal() * z * prior.chol_v.transpose();
    const Eigen::VectorXd x = sample.ToVector().cwiseMax(lower).cwiseMin(upper);
    ++pb->evaluations;
    Evaluate(pb, x.data(), n);
  }
  if (!pb->have_feasible && !pb->failed && !out_of_time()) {
    Eigen::VectorXd theta = pb->fallback.x;
    nlopt_result r = nlopt_set_lower_bounds(lbfgs.get(), lower.data());
    if (r > 0) r = nlopt_set_upper_bounds(lbfgs.get(), upper.data());
    if (r > 0) r = nlopt_set_min_objective(lbfgs.get(), Callback<Value::kCost>, pb);
    if (r > 0) r = nlopt_set_stopval(lbfgs.get(), options.epsilon - options.tolerance);
    if (r > 0) r = nlopt_set_xtol_rel(lbfgs.get(), options.xtol_rel);
    if (r > 0) r = nlopt_set_maxeval(lbfgs.get(), options.max_evaluations);
    if (r > 0 && seconds_left > 0) r = nlopt_set_maxtime(lbfgs.get(), seconds_left);
    double c = 0;
    if (r > 0) nlopt_optimize(lbfgs.get(), theta.data(), &c);
  }
  if (!pb->have_feasible) pb->fallback = fallback;
  return pb->have_feasible && !pb->failed;
}

}  // namespace

ProjectionSummary ProjectComponent(const ComponentParams& prior, const ConstraintFunction& cost,
                                   const ProjectionOptions& options, ComponentParams* out) {
  return ProjectComponent(prior, cost, options, out, prior);
}

ProjectionSummary ProjectComponent(const ComponentParams& prior, const ConstraintFunction& cost,
                                   const ProjectionOptions& options, ComponentParams* out,
                                   const ComponentParams& warm_start) {
  // Bad arguments are caller errors and throw; everything after them is reported as a status.
  FS_THROW_UNLESS(out != nullptr, "ProjectComponent: out is null");
  FS_THROW_UNLESS(static_cast<bool>(cost), "ProjectComponent: the constraint function is empty");
  FS_THROW_UNLESS(std::isfinite(options.epsilon),
                  "ProjectComponent: options.epsilon must be finite, got ", options.epsilon);
  FS_THROW_UNLESS(std::isfinite(options.tolerance) && options.tolerance >= 0,
                  "ProjectComponent: options.tolerance must be finite and >= 0, got ",
                  options.tolerance);
  FS_THROW_UNLESS(std::isfinite(options.xtol_rel) && options.xtol_rel >= 0,
                  "ProjectComponent: options.xtol_rel must be finite and >= 0, got ",
                  options.xtol_rel);
  FS_THROW_UNLESS(options.max_evaluations >= 1,
                  "ProjectComponent: options.max_evaluations must be >= 1, got ",
                  options.max_evaluations);
  FS_THROW_UNLESS(std::isfinite(options.max_seconds) && options.max_seconds >= 0,
                  "ProjectComponent: options.max_seconds must be finite and >= 0, got ",
                  options.max_seconds);
  FS_THROW_UNLESS(prior.mean.cols() == 2 && prior.mean.rows() >= 1,
                  "ProjectComponent: prior.mean must be m x 2 with m >= 1, got ", prior.mean.rows(),
                  " x ", prior.mean.cols());
  FS_THROW_UNLESS(prior.log_u.size() == prior.mean.rows(), "ProjectComponent: prior.log_u has ",
                  prior.log_u.size(), " entries, the mean has ", prior.mean.rows(), " rows");

  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const ComponentParams prior_copy = prior;  // `out` may alias `prior` (or `start`)
  const bool warm = &warm_start != &prior && AllFinite(warm_start) && warm_start.chol_v(0, 0) > 0 &&
                    warm_start.chol_v(1, 1) > 0 && warm_start.mean.rows() == prior.mean.rows() &&
                    warm_start.mean.cols() == 2 && warm_start.log_u.size() == prior.log_u.size();
  const ComponentParams start_copy = warm ? warm_start : ComponentParams{};
  ProjectionSummary summary;
  summary.status = ProjectionStatus::kFailed;
  const auto finish_with_prior = [&](ProjectionStatus status) {
    summary.status = status;
    summary.kl = 0;
    summary.cost = summary.prior_cost;
    summary.seconds = elapsed();
    *out = prior_copy;
    return summary;
  };

  // A prior that is not a valid component (non-finite, non-positive L_V diagonal) is a numeric
  // failure of whatever produced it.
  if (!AllFinite(prior) || !(prior.chol_v(0, 0) > 0) || !(prior.chol_v(1, 1) > 0)) {
    summary.prior_cost = std::numeric_limits<double>::quiet_NaN();
    return finish_with_prior(ProjectionStatus::kFailed);
  }
  try {
    summary.prior_cost = cost(prior_copy, nullptr);
  } catch (...) {
    summary.prior_cost = std::numeric_limits<double>::quiet_NaN();
  }
  if (!std::isfinite(summary.prior_cost)) return finish_with_prior(ProjectionStatus::kFailed);
  if (summary.prior_cost <= options.epsilon) {
    return finish_with_prior(ProjectionStatus::kAlreadyFeasible);
  }

  const int m = prior.basis();
  const Eigen::VectorXd prior_theta = prior_copy.ToVector();
  Eigen::VectorXd theta = prior_theta;
  // The warm start's C and KL (a start that cannot be evaluated is dropped: the prior is used).
  double start_cost = NAN, start_kl = NAN;
  if (warm) {
    try {
      start_cost = cost(start_copy, nullptr);
      start_kl = MatrixNormalKl(start_copy, prior_copy, nullptr);
    } catch (...) {
      start_cost = NAN;
    }
  }
  const bool use_start = warm && std::isfinite(start_cost) && std::isfinite(start_kl);
  const unsigned n = static_cast<unsigned>(theta.size());
  std::unique_ptr<nlopt_opt_s, OptDeleter> opt(nlopt_create(NLOPT_LD_SLSQP, n));
  if (!opt) return finish_with_prior(ProjectionStatus::kFailed);

  Problem pb;
  pb.prior = &prior_copy;
  pb.cost = &cost;
  pb.opt = opt.get();
  pb.basis = m;
  pb.epsilon = options.epsilon;
  pb.feasible_limit = options.epsilon + options.tolerance;
  pb.work.Resize(m);
  pb.tolerance = options.tolerance;
  pb.fallback.min_cost = summary.prior_cost;
  pb.fallback.x = theta;
  pb.fallback.cost = summary.prior_cost;
  pb.fallback.kl = 0;
  if (use_start) {
    theta = start_copy.ToVector();
    if (start_cost < pb.fallback.min_cost) {
      pb.fallback.min_cost = start_cost;
      pb.fallback.x = theta;
      pb.fallback.cost = start_cost;
      pb.fallback.kl = start_kl;
      pb.fallback.moved = true;
    }
    if (start_cost <= pb.feasible_limit) {
      pb.have_feasible = true;
      pb.best_feasible = theta;
      pb.best_feasible_kl = start_kl;
      pb.best_feasible_cost = start_cost;
    }
  }

  // Box bounds around the prior keep every exp() finite during SLSQP's line searches: the
  // log-variances of U and the log-diagonal of L_V move by at most kLogRange, the means are free.
  constexpr double kLogRange = 8.0;
  Eigen::VectorXd lower = Eigen::VectorXd::Constant(n, -HUGE_VAL);
  Eigen::VectorXd upper = Eigen::VectorXd::Constant(n, HUGE_VAL);
  for (int i = 2 * m; i < static_cast<int>(n); ++i) {
    if (i == 3 * m + 1) continue;  // L_V(1, 0) is not a log
    lower[i] = prior_theta[i] - kLogRange;
    upper[i] = prior_theta[i] + kLogRange;
  }
  // The prior lies inside its bounds; a warm start from an earlier solve under the same bounds too,
  // up to round-off.
  theta = theta.cwiseMax(lower).cwiseMin(upper);
  nlopt_result r = nlopt_set_lower_bounds(opt.get(), lower.data());
  if (r > 0) r = nlopt_set_upper_bounds(opt.get(), upper.data());
  if (r > 0) r = nlopt_set_min_objective(opt.get(), Callback<Value::kKl>, &pb);
  if (r > 0)
    r = nlopt_add_inequality_constraint(opt.get(), Callback<Value::kConstraint>, &pb,
                                        options.tolerance);
  if (r > 0) r = nlopt_set_xtol_rel(opt.get(), options.xtol_rel);
  if (r > 0) r = nlopt_set_maxeval(opt.get(), options.max_evaluations);
  if (r > 0 && options.max_seconds > 0) r = nlopt_set_maxtime(opt.get(), options.max_seconds);
  double final_kl = 0;
  const auto out_of_time = [&] {
    return options.max_seconds > 0 && elapsed() >= options.max_seconds;
  };
  // A fresh evaluation budget for another SLSQP attempt, within what is left of max_seconds.
  const auto renew_budget = [&] {
    nlopt_result b = nlopt_set_maxeval(opt.get(), options.max_evaluations);
    if (b > 0 && options.max_seconds > 0)
      b = nlopt_set_maxtime(opt.get(), options.max_seconds - elapsed());
    return b;
  };
  // SLSQP may stop without a feasible point (a line search that cannot make progress from where
  // the linearisation led it); it then restarts from the lowest-cost point seen, each attempt with
  // max_evaluations, all within max_seconds.
  const bool set_up = r > 0;
  for (int attempt = 0; set_up && attempt <= options.restarts; ++attempt) {
    if (attempt > 0) {
      if (pb.have_feasible || pb.failed) break;
      if (out_of_time()) break;
      theta = pb.fallback.x;
      r = renew_budget();
      if (r <= 0) break;  // a setter failed: judged below like any other stop
    }
    r = nlopt_optimize(opt.get(), theta.data(), &final_kl);
    if (pb.failed || r == NLOPT_FORCED_STOP || r == NLOPT_INVALID_ARGS || r == NLOPT_OUT_OF_MEMORY)
      break;
  }
  // Phase I, then SLSQP again from the feasible point it found.
  if (set_up && options.feasibility_phase && !pb.have_feasible && !pb.failed &&
      r != NLOPT_FORCED_STOP && r != NLOPT_INVALID_ARGS && r != NLOPT_OUT_OF_MEMORY &&
      !out_of_time()) {
    const double seconds_left = options.max_seconds > 0 ? options.max_seconds - elapsed() : 0;
    const bool found = SeekFeasiblePoint(&pb, prior_copy, lower, upper, options, seconds_left);
    pb.opt = opt.get();
    if (found && !out_of_time()) {
      theta = pb.best_feasible;
      r = renew_budget();
      if (r > 0) r = nlopt_optimize(opt.get(), theta.data(), &final_kl);
    }
    if (pb.failed) r = NLOPT_FORCED_STOP;
  }
  summary.nlopt_result = ResultName(r);
  summary.evaluations = pb.evaluations;

  // Our forced stop (a callback failed) or an NLopt error proper: the prior is returned. Any other
  // stop (converged, limits, round-off, SLSQP's generic failure such as incompatible linearised
  // constraints) is judged by the points visited: the lowest-KL feasible one if any, else the
  // (near-)lowest-cost one (the solver may end elsewhere).
  if (pb.failed || r == NLOPT_FORCED_STOP || r == NLOPT_INVALID_ARGS || r == NLOPT_OUT_OF_MEMORY) {
    return finish_with_prior(ProjectionStatus::kFailed);
  }
  try {
    if (pb.have_feasible) {
      summary.status = ProjectionStatus::kSolved;
      summary.kl = pb.best_feasible_kl;
      summary.cost = pb.best_feasible_cost;
      *out = ComponentParams::FromVector(pb.best_feasible, m);
    } else {
      if (!pb.fallback.moved) return finish_with_prior(ProjectionStatus::kInfeasible);
      summary.status = ProjectionStatus::kInfeasible;
      summary.kl = pb.fallback.kl;
      summary.cost = pb.fallback.cost;
      *out = ComponentParams::FromVector(pb.fallback.x, m);
    }
  } catch (...) {  // not reached: every stored point was finite when evaluated
    return finish_with_prior(ProjectionStatus::kFailed);
  }
  summary.seconds = elapsed();
  return summary;
}

}  // namespace foresight::constrained
