#include "inference/constrained/distribution_projector.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <utility>

#include "core/error.h"
#include "inference/constrained/kl.h"

namespace foresight::constrained {

namespace {

/// Component r of d into *p without allocating once p has d's basis.
void FillComponentParams(const TrajectoryDistribution& d, int r, ComponentParams* p) {
  FS_THROW_UNLESS(r >= 0 && r < d.components(), "ToComponentParams: component ", r,
                  " out of range [0, ", d.components(), ")");
  const Eigen::MatrixXd& lu = d.chol_u(r);
  const int m = d.basis_size();
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < m; ++i) {
      FS_THROW_UNLESS(i == j || lu(i, j) == 0,
                      "ToComponentParams: the projection needs u_param: diagonal, but L_U(", i,
                      ", ", j, ") of component ", r, " is ", lu(i, j));
    }
  }
  p->mean = d.mean(r);
  if (p->log_u.size() != m) p->log_u.resize(m);
  for (int i = 0; i < m; ++i) p->log_u[i] = 2 * std::log(lu(i, i));
  p->chol_v = d.chol_v(r);
}

}  // namespace

ComponentParams ToComponentParams(const TrajectoryDistribution& d, int r) {
  ComponentParams p;
  FillComponentParams(d, r, &p);
  return p;
}

void SetFromComponentParams(const ComponentParams& p, int r, TrajectoryDistribution* d) {
  FS_THROW_UNLESS(d != nullptr, "SetFromComponentParams: distribution is null");
  const int m = d->basis_size();
  FS_THROW_UNLESS(p.mean.rows() == m && p.mean.cols() == 2 && p.log_u.size() == m,
                  "SetFromComponentParams: parameters of basis ", p.mean.rows(), " (mean ",
                  p.mean.rows(), " x ", p.mean.cols(), ", log_u ", p.log_u.size(),
                  ") for a distribution of basis ", m);
  const Eigen::MatrixXd lu = (0.5 * p.log_u.array()).exp().matrix().asDiagonal();
  d->SetComponent(r, p.mean, lu, p.chol_v);
}

DistributionProjector::DistributionProjector(const occupancy::Map* map, const TimeBasis& basis,
                                             Eigen::VectorXd times, const ProjectorOptions& options)
    : options_(options), cost_(map, basis, std::move(times), options.order) {
  FS_THROW_UNLESS(std::isfinite(options_.epsilon) && options_.epsilon > 0 && options_.epsilon < 1,
                  "DistributionProjector: epsilon must be in (0, 1), got ", options_.epsilon);
  FS_THROW_UNLESS(
      std::isfinite(options_.margin) && options_.margin >= 0 && options_.margin < options_.epsilon,
      "DistributionProjector: margin must be in [0, epsilon = ", options_.epsilon, "), got ",
      options_.margin);
  const ProjectionOptions& s = options_.solver;
  FS_THROW_UNLESS(std::isfinite(s.tolerance) && s.tolerance >= 0,
                  "DistributionProjector: solver.tolerance must be finite and >= 0, got ",
                  s.tolerance);
  FS_THROW_UNLESS(std::isfinite(s.xtol_rel) && s.xtol_rel >= 0,
                  "DistributionProjector: solver.xtol_rel must be finite and >= 0, got ",
                  s.xtol_rel);
  FS_THROW_UNLESS(s.max_evaluations >= 1,
                  "DistributionProjector: solver.max_evaluations must be >= 1, got ",
                  s.max_evaluations);
  FS_THROW_UNLESS(std::isfinite(s.max_seconds) && s.max_seconds >= 0,
                  "DistributionProjector: solver.max_seconds must be finite and >= 0, got ",
                  s.max_seconds);
  FS_THROW_UNLESS(options_.check_order == 0, "DistributionProjector: check_order ",
                  options_.check_order,
                  " needs the check operator's times (the constructor with "
                  "check_times)");
  options_.solver.epsilon = options_.epsilon - options_.margin;
}

namespace {
ProjectorOptions WithoutCheck(ProjectorOptions o) {
  o.check_order = 0;
  return o;
}
}  // namespace

DistributionProjector::DistributionProjector(const occupancy::Map* map, const TimeBasis& basis,
                                             Eigen::VectorXd times, const ProjectorOptions& options,
                                             Eigen::VectorXd check_times)
    : DistributionProjector(map, basis, std::move(times), WithoutCheck(options)) {
  options_.check_order = options.check_order;
  FS_THROW_UNLESS(options_.check_order >= 1 && options_.check_order <= 64,
                  "DistributionProjector: check_order must be in [1, 64] with check times, got ",
                  options_.check_order);
  FS_THROW_UNLESS(options_.check_rounds >= 0,
                  "DistributionProjector: check_rounds must be >= 0, got ", options_.check_rounds);
  FS_THROW_UNLESS(std::isfinite(options_.check_slack) && options_.check_slack >= 0 &&
                      (options_.check_slack == 0 || options_.check_slack < options_.margin),
                  "DistributionProjector: check_slack must be in [0, margin = ", options_.margin,
                  "), got ", options_.check_slack);
  check_.emplace(map, basis, std::move(check_times), options_.check_order);
}

DistributionProjector::Workspace DistributionProjector::MakeWorkspace() const {
  Workspace ws;
  ws.cost = cost_.MakeWorkspace();
  if (check_) {
    ws.check = check_->MakeWorkspace();
    ws.check.offset.resize(2, check_->times().size());
  }
  ws.cost.offset.resize(2, cost_.times().size());
  ws.gradient.Resize(cost_.basis());
  ws.component.mean.resize(cost_.basis(), 2);
  ws.component.log_u.resize(cost_.basis());
  return ws;
}

void DistributionProjector::SetOffset(const TrajectoryDistribution& d, const Eigen::VectorXd& t,
                                      Eigen::Matrix2Xd* offset) {
  if (offset->cols() != t.size()) offset->resize(2, t.size());
  for (Eigen::Index k = 0; k < t.size(); ++k) offset->col(k) = d.origin() + t[k] * d.velocity();
}

namespace {
/// No component ended infeasible or failed.
bool AllSolved(const TrackProjection& r) {
  for (const ProjectionSummary& s : r.components)
    if (s.status == ProjectionStatus::kInfeasible || s.status == ProjectionStatus::kFailed)
      return false;
  return true;
}

void CheckBasis(const TrajectoryDistribution& d, const CollisionCost& cost) {
  FS_THROW_UNLESS(d.basis_size() == cost.basis(), "DistributionProjector: the distribution has ",
                  d.basis_size(), " basis functions, the projector's basis has ", cost.basis());
}
}  // namespace

double DistributionProjector::Cost(const TrajectoryDistribution& d, Workspace* ws) const {
  FS_THROW_UNLESS(ws != nullptr, "DistributionProjector::Cost: workspace is null");
  CheckBasis(d, cost_);
  SetOffset(d, cost_.times(), &ws->cost.offset);
  double total = 0;
  for (int r = 0; r < d.components(); ++r) {
    FillComponentParams(d, r, &ws->component);
    total += d.alpha(r) * cost_.Component(ws->component, &ws->cost, nullptr);
  }
  return total;
}

double DistributionProjector::CheckCost(const TrajectoryDistribution& d, Workspace* ws) const {
  try {
    SetOffset(d, check_->times(), &ws->check.offset);
    double total = 0;
    for (int r = 0; r < d.components(); ++r) {
      FillComponentParams(d, r, &ws->component);
      total += d.alpha(r) * check_->Component(ws->component, &ws->check, nullptr);
    }
    return total;
  } catch (const std::exception&) {
    return std::nan("");
  }
}

TrackProjection DistributionProjector::Project(const TrajectoryDistribution& prior,
                                               TrajectoryDistribution* out, Workspace* ws) const {
  const auto start = std::chrono::steady_clock::now();
  FS_THROW_UNLESS(out != nullptr, "DistributionProjector::Project: out is null");
  FS_THROW_UNLESS(ws != nullptr, "DistributionProjector::Project: workspace is null");
  FS_THROW_UNLESS(
      out->components() == prior.components() && out->basis_size() == prior.basis_size(),
      "DistributionProjector::Project: out has ", out->components(), " components of basis ",
      out->basis_size(), ", the prior ", prior.components(), " of basis ", prior.basis_size());
  CheckBasis(prior, cost_);
  const double target0 = options_.solver.epsilon;  // epsilon - margin
  const auto seconds = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  if (!check_) {
    TrackProjection result =
        ProjectOnce(prior, out, ws, cost_, &ws->cost, options_.epsilon, target0);
    result.seconds = seconds();
    return result;
  }
  // `out` may be the prior: the repeated solves start from a copy then.
  std::optional<TrajectoryDistribution> prior_copy;
  if (out == &prior) prior_copy = prior;
  const TrajectoryDistribution& from = prior_copy ? *prior_copy : prior;
  TrackProjection result = ProjectOnce(from, out, ws, cost_, &ws->cost, options_.epsilon, target0);
  const double prior_cost = result.prior_cost;  // the configured operator's, kept throughout
  bool changed = result.changed;
  int evaluations = result.evaluations;
  // The repeated solves, each warm-started at the last solution: first (when the configured
  // operator did solve every component) the configured operator again with its target lowered by
  // the excess the check found, which is cheap and mends a small gap; then the check operator
  // itself, and then the check operator with its target lowered by the excess it left.
  double configured_target = target0, check_target = target0;
  int check_solves = 0;
  // A prior the configured rule passed, or a configured solve that ended infeasible: straight to
  // the check operator.
  bool on_check = !result.changed || !AllSolved(result);
  for (int round = 0;; ++round) {
    result.prior_cost = prior_cost;
    result.checked_cost = CheckCost(*out, ws);
    result.check_rounds = round;
    result.evaluations = evaluations;
    result.changed = changed;
    if (!std::isfinite(result.checked_cost) || result.status == "failed") {
      result.feasible = false;
      result.status = "failed";
      break;
    }
    // The check operator is the more accurate one: its verdict is the result's.
    if (result.checked_cost <= options_.epsilon - options_.check_slack) {
      result.feasible = true;
      result.status = changed ? "solved" : "compliant_prior";
      break;
    }
    result.feasible = false;
    result.status = "infeasible";
    if (round == options_.check_rounds) break;
    const double excess = result.checked_cost - target0;
    const TrajectoryDistribution previous = *out;
    // A repeated solve that fails outright keeps the last result (infeasible by the check).
    const auto solve_again = [&](const CollisionCost& op, CollisionCost::Workspace* op_ws,
                                 double target) {
      TrackProjection next = ProjectOnce(from, out, ws, op, op_ws, -HUGE_VAL, target, &previous);
      evaluations += next.evaluations;
      if (next.status == "failed") {
        *out = previous;
        result.evaluations = evaluations;
        return false;
      }
      result = std::move(next);
      changed = true;
      return true;
    };
    if (!on_check) {
      on_check = true;
      configured_target -= excess;
      if (configured_target > 0) {
        if (!solve_again(cost_, &ws->cost, configured_target)) break;
        continue;
      }
    } else if (check_solves > 0) {
      // A solve against the check operator itself found no compliant point: a lower target will
      // not; else lower its target by the excess it left.
      if (!AllSolved(result)) break;
      check_target -= excess;
      if (!(check_target > 0)) break;
    }
    ++check_solves;
    if (!solve_again(*check_, &ws->check, check_target)) break;
  }
  result.seconds = seconds();
  return result;
}

TrackProjection DistributionProjector::ProjectOnce(const TrajectoryDistribution& prior,
                                                   TrajectoryDistribution* out, Workspace* ws,
                                                   const CollisionCost& op,
                                                   CollisionCost::Workspace* op_ws,
                                                   double mixture_limit, double target,
                                                   const TrajectoryDistribution* start) const {
  SetOffset(prior, op.times(), &op_ws->offset);
  const int R = prior.components();
  // The prior's components, copied before `out` (which may be the prior) is written.
  std::vector<ComponentParams> params(static_cast<std::size_t>(R));
  for (int r = 0; r < R; ++r) params[static_cast<std::size_t>(r)] = ToComponentParams(prior, r);
  std::vector<ComponentParams> starts;
  if (start != nullptr)
    for (int r = 0; r < R; ++r) starts.push_back(ToComponentParams(*start, r));
  if (out != &prior) *out = prior;

  TrackProjection result;
  result.components.resize(static_cast<std::size_t>(R));
  const auto finish = [&]() { return result; };
  const auto worst = [&](const char* s) {
    static const char* const kOrder[] = {"compliant_prior", "solved", "infeasible", "failed"};
    int now = 0, next = 0;
    for (int i = 0; i < 4; ++i) {
      if (result.status == kOrder[i]) now = i;
      if (std::string(s) == kOrder[i]) next = i;
    }
    if (next > now) result.status = s;
  };

  // Per-component costs of the prior (a throwing map is a failure, not an exception here).
  std::vector<double> prior_costs(static_cast<std::size_t>(R), 0.0);
  try {
    for (int r = 0; r < R; ++r) {
      const auto k = static_cast<std::size_t>(r);
      prior_costs[k] = op.Component(params[k], op_ws, nullptr);
      result.prior_cost += prior.alpha(r) * prior_costs[k];
    }
  } catch (const std::exception&) {
    result.prior_cost = std::nan("");
  }
  result.cost = result.prior_cost;
  if (!std::isfinite(result.prior_cost)) {
    result.status = "failed";
    for (int r = 0; r < R; ++r) {
      ProjectionSummary& s = result.components[static_cast<std::size_t>(r)];
      s.status = ProjectionStatus::kFailed;
      s.prior_cost = s.cost = prior_costs[static_cast<std::size_t>(r)];
    }
    return finish();
  }
  if (result.prior_cost <= mixture_limit) {
    result.feasible = result.prior_cost <= options_.epsilon;
    result.status = "compliant_prior";
    for (int r = 0; r < R; ++r) {
      ProjectionSummary& s = result.components[static_cast<std::size_t>(r)];
      s.status = ProjectionStatus::kAlreadyFeasible;
      s.prior_cost = s.cost = prior_costs[static_cast<std::size_t>(r)];
    }
    return finish();
  }

  result.changed = true;
  result.status = "solved";
  CollisionCost::Workspace* cost_ws = op_ws;
  const CollisionCost* cost = &op;
  const ConstraintFunction constraint = [cost, cost_ws](const ComponentParams& p,
                                                        ComponentGradient* g) {
    return cost->Component(p, cost_ws, g);
  };
  ProjectionOptions solver = options_.solver;
  solver.epsilon = target;
  for (int r = 0; r < R; ++r) {
    const auto k = static_cast<std::size_t>(r);
    ProjectionSummary& s = result.components[k];
    if (prior_costs[k] <= target) {
      s.status = ProjectionStatus::kAlreadyFeasible;
      s.prior_cost = s.cost = prior_costs[k];
      continue;
    }
    try {
      s = starts.empty()
              ? ProjectComponent(params[k], constraint, solver, &ws->component)
              : ProjectComponent(params[k], constraint, solver, &ws->component, starts[k]);
      if (s.status == ProjectionStatus::kSolved || s.status == ProjectionStatus::kInfeasible) {
        SetFromComponentParams(ws->component, r, out);
      }
    } catch (const std::exception&) {
      s = ProjectionSummary{};
      s.status = ProjectionStatus::kFailed;
      s.prior_cost = s.cost = prior_costs[k];
      SetFromComponentParams(params[k], r, out);
    }
    result.evaluations += s.evaluations;
    result.kl += prior.alpha(r) * s.kl;
    if (s.status == ProjectionStatus::kFailed) worst("failed");
    if (s.status == ProjectionStatus::kInfeasible) worst("infeasible");
  }

  // The returned mixture's C, recomputed on the result (never the solver's word).
  try {
    result.cost = Cost(*out, ws);
  } catch (const std::exception&) {
    result.cost = std::nan("");
  }
  result.feasible = std::isfinite(result.cost) && result.cost <= options_.epsilon;
  if (!result.feasible) worst("infeasible");
  return finish();
}

}  // namespace foresight::constrained
