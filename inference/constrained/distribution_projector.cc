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
  options_.solver.epsilon = options_.epsilon - options_.margin;
}

DistributionProjector::Workspace DistributionProjector::MakeWorkspace() const {
  Workspace ws;
  ws.cost = cost_.MakeWorkspace();
  ws.cost.offset.resize(2, cost_.times().size());
  ws.gradient.Resize(cost_.basis());
  ws.component.mean.resize(cost_.basis(), 2);
  ws.component.log_u.resize(cost_.basis());
  return ws;
}

void DistributionProjector::SetOffset(const TrajectoryDistribution& d, Workspace* ws) const {
  FS_THROW_UNLESS(d.basis_size() == cost_.basis(), "DistributionProjector: the distribution has ",
                  d.basis_size(), " basis functions, the projector's basis has ", cost_.basis());
  const Eigen::VectorXd& t = cost_.times();
  if (ws->cost.offset.cols() != t.size()) ws->cost.offset.resize(2, t.size());
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    ws->cost.offset.col(k) = d.origin() + t[k] * d.velocity();
  }
}

double DistributionProjector::Cost(const TrajectoryDistribution& d, Workspace* ws) const {
  FS_THROW_UNLESS(ws != nullptr, "DistributionProjector::Cost: workspace is null");
  SetOffset(d, ws);
  double total = 0;
  for (int r = 0; r < d.components(); ++r) {
    FillComponentParams(d, r, &ws->component);
    total += d.alpha(r) * cost_.Component(ws->component, &ws->cost, nullptr);
  }
  return total;
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
  SetOffset(prior, ws);  // checks the basis size
  const int R = prior.components();
  // The prior's components, copied before `out` (which may be the prior) is written.
  std::vector<ComponentParams> params(static_cast<std::size_t>(R));
  for (int r = 0; r < R; ++r) params[static_cast<std::size_t>(r)] = ToComponentParams(prior, r);
  if (out != &prior) *out = prior;

  TrackProjection result;
  result.components.resize(static_cast<std::size_t>(R));
  const auto finish = [&]() {
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
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
      prior_costs[k] = cost_.Component(params[k], &ws->cost, nullptr);
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
  if (result.prior_cost <= options_.epsilon) {
    result.feasible = true;
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
  CollisionCost::Workspace* cost_ws = &ws->cost;
  const CollisionCost* cost = &cost_;
  const ConstraintFunction constraint = [cost, cost_ws](const ComponentParams& p,
                                                        ComponentGradient* g) {
    return cost->Component(p, cost_ws, g);
  };
  const double target = options_.solver.epsilon;
  for (int r = 0; r < R; ++r) {
    const auto k = static_cast<std::size_t>(r);
    ProjectionSummary& s = result.components[k];
    if (prior_costs[k] <= target) {
      s.status = ProjectionStatus::kAlreadyFeasible;
      s.prior_cost = s.cost = prior_costs[k];
      continue;
    }
    try {
      s = ProjectComponent(params[k], constraint, options_.solver, &ws->component);
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
