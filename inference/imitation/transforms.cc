#include "inference/imitation/transforms.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/error.h"

namespace foresight::imitation {

// ---- obstacle transform ----------------------------------------------------------------------

template <int D>
ObstacleTransform<D>::ObstacleTransform(OccupancyField<D> field, FlowSettings<D> settings,
                                        ObstacleGate<D> gate)
    : field_(std::move(field)), settings_(settings), gate_(gate) {
  FS_THROW_UNLESS(
      gate_.goal.allFinite() && std::isfinite(gate_.length) && gate_.length >= 0,
      "obstacle transform: the goal gate needs a finite goal and length >= 0, got goal (",
      gate_.goal.transpose(), ") length ", gate_.length);
  FS_THROW_UNLESS(std::isfinite(settings_.time) && settings_.time > 0,
                  "obstacle transform: flow time ", settings_.time, " must be positive and finite");
  FS_THROW_UNLESS(settings_.steps >= 1, "obstacle transform: flow steps ", settings_.steps,
                  " must be at least 1");
  const RbfGrid<D>& g = field_.grid();
  const double max_w = field_.weights().size() ? field_.weights().cwiseAbs().maxCoeff() : 0.0;
  discontinuity_ = 2 * g.truncation() * max_w * (g.gamma() * g.spec().cutoff_radius + 1);
}

template <int D>
Vec<D> ObstacleTransform<D>::Field(const Vec<D>& s, RbfFeatures<D>* ws, Mat<D>* jacobian) const {
  OccupancyValue<D> v;
  field_.Evaluate(s, ws, jacobian != nullptr, &v);
  if (gate_.length <= 0) {
    if (jacobian != nullptr) *jacobian = v.hessian;
    return v.gradient;
  }
  // w grad p and its Jacobian w Hess p + grad p grad w'.
  Vec<D> grad_w;
  const double w = gate_.Weight(s, &grad_w);
  if (jacobian != nullptr) *jacobian = w * v.hessian + v.gradient * grad_w.transpose();
  return w * v.gradient;
}

// s_{k+1} = s_k + h V_o(s_k),  J_{k+1} = (I + h dV_o(s_k)) J_k  (V_o = grad p without a gate).
template <int D>
Vec<D> ObstacleTransform<D>::Forward(const Vec<D>& y, RbfFeatures<D>* ws, Mat<D>* jacobian) const {
  const double h = settings_.time / settings_.steps;
  const bool with_jacobian = jacobian != nullptr;
  Vec<D> s = y;
  Mat<D> j = Mat<D>::Identity();
  Mat<D> dv = Mat<D>::Zero();
  for (int k = 0; k < settings_.steps; ++k) {
    const Vec<D> v = Field(s, ws, with_jacobian ? &dv : nullptr);
    // Where the field (and, when asked, its Jacobian) is exactly zero, e.g. outside the map's
    // support (no feature within the cut-off) or at the gate's goal, s and J would stay as they
    // are for every remaining step (the field is autonomous): stopping gives the same values (up
    // to the sign of a zero).
    if (v.isZero(0) && (!with_jacobian || dv.isZero(0))) break;
    if (with_jacobian) j = (Mat<D>::Identity() + h * dv) * j;
    s += h * v;
  }
  if (with_jacobian) *jacobian = j;
  return s;
}

template <int D>
bool ObstacleTransform<D>::Inverse(const Vec<D>& x, RbfFeatures<D>* ws, Vec<D>* y, double tolerance,
                                   int max_iterations) const {
  const double h = settings_.time / settings_.steps;
  return detail::InvertEulerMap<D>(
      x, settings_.steps, h, [&](const Vec<D>& s, int) { return Field(s, ws); }, tolerance,
      h * discontinuity_, max_iterations, y);
}

// ---- bias transform --------------------------------------------------------------------------

// min_W sum_i ||u_i - W' phi(s_i)||^2 + lambda ||W||_F^2,  u_i = (s_i - s_tar) / ||s_i - s_tar||.
// Only states some sample touches enter the normal equations (the others' weights are 0).
template <int D>
RbfFlow<D> FitBiasTransform(const RbfGrid<D>& grid, const Eigen::Matrix<double, D, -1>& samples,
                            const Vec<D>& target, double lambda, FlowSettings<D> settings) {
  FS_THROW_UNLESS(std::isfinite(lambda) && lambda > 0, "bias transform: ridge weight ", lambda,
                  " must be positive and finite");
  FS_THROW_UNLESS(target.allFinite(), "bias transform: target (", target.transpose(),
                  ") is not finite");
  FS_THROW_UNLESS(samples.cols() > 0 && samples.allFinite(), "bias transform: ", samples.cols(),
                  " samples; expected at least one, all finite");
  const auto features = std::make_unique<RbfFeatures<D>>();  // large for D = 3: not on the stack
  RbfFeatures<D>& f = *features;
  std::unordered_map<int, int> local;  // inducing state -> row of the normal equations
  std::vector<int> states;
  for (Eigen::Index i = 0; i < samples.cols(); ++i) {
    grid.Evaluate(samples.col(i), &f);
    for (int k = 0; k < f.count; ++k)
      if (local.emplace(f.index[k], static_cast<int>(states.size())).second)
        states.push_back(f.index[k]);
  }
  const int n = static_cast<int>(states.size());
  FS_THROW_UNLESS(n > 0, "bias transform: no sample lies within the grid's cut-off radius");
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(n, n) * lambda;
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(n, D);
  std::vector<int> rows(RbfFeatures<D>::kCapacity);
  for (Eigen::Index i = 0; i < samples.cols(); ++i) {
    const Vec<D> d = samples.col(i) - target;
    const double norm = d.norm();
    if (norm == 0) continue;  // no direction at the target itself
    const Vec<D> u = d / norm;
    grid.Evaluate(samples.col(i), &f);
    for (int k = 0; k < f.count; ++k) rows[k] = local.at(f.index[k]);
    for (int k = 0; k < f.count; ++k) {
      b.row(rows[k]) += f.phi[k] * u.transpose();
      for (int l = 0; l < f.count; ++l) a(rows[k], rows[l]) += f.phi[k] * f.phi[l];
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(a);
  FS_THROW_UNLESS(llt.info() == Eigen::Success, "bias transform: the ridge system is singular");
  const Eigen::MatrixXd w_local = llt.solve(b);
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(grid.size(), D);
  for (int r = 0; r < n; ++r) w.row(states[r]) = w_local.row(r);
  return RbfFlow<D>(grid, std::move(w), settings, "bias transform");
}

// ---- composition -----------------------------------------------------------------------------

template <int D>
ComposedSystem<D>::ComposedSystem(ImitationSystem<D> imitation,
                                  std::vector<OuterTransform<D>> outer)
    : imitation_(std::move(imitation)), outer_(std::move(outer)) {}

template <int D>
ComposedWorkspace<D> ComposedSystem<D>::MakeWorkspace() const {
  ComposedWorkspace<D> ws;
  ws.imitation = imitation_.flow().MakeWorkspace();
  for (const OuterTransform<D>& t : outer_) {
    if (t.type == OuterTransform<D>::Type::kObstacle) {
      ws.obstacle.push_back(t.obstacle.MakeWorkspace());
    } else {
      ws.bias.push_back(t.bias.MakeWorkspace());
    }
  }
  return ws;
}

// Outside in: y_n = y, y_{j-1} = psi_j(y_j), x = y_0; the chain rule gives
// d x / d y = J_1 J_2 ... J_n, so y_dot = (J_1 ... J_n)^-1 f_i(x) = J_n^-1 ... J_1^-1 f_i(x).
template <int D>
Vec<D> ComposedSystem<D>::Velocity(const Vec<D>& y, ComposedWorkspace<D>* ws) const {
  Vec<D> s = y;
  Mat<D> chain = Mat<D>::Identity(), j;
  std::size_t obstacle = ws->obstacle.size(), bias = ws->bias.size();
  for (std::size_t t = outer_.size(); t-- > 0;) {
    const OuterTransform<D>& o = outer_[t];
    if (o.type == OuterTransform<D>::Type::kObstacle) {
      s = o.obstacle.Forward(s, ws->obstacle[--obstacle].get(), &j);
    } else {
      s = o.bias.Forward(s, &ws->bias[--bias], &j);
    }
    chain = j * chain;
  }
  const Vec<D> f = imitation_.Velocity(s, &ws->imitation);
  if (outer_.empty()) return f;
  return chain.partialPivLu().solve(f);
}

template <int D>
Vec<D> ComposedSystem<D>::Inner(const Vec<D>& y, ComposedWorkspace<D>* ws) const {
  Vec<D> s = y;
  std::size_t obstacle = ws->obstacle.size(), bias = ws->bias.size();
  for (std::size_t t = outer_.size(); t-- > 0;) {
    const OuterTransform<D>& o = outer_[t];
    if (o.type == OuterTransform<D>::Type::kObstacle) {
      s = o.obstacle.Forward(s, ws->obstacle[--obstacle].get());
    } else {
      s = o.bias.Forward(s, &ws->bias[--bias]);
    }
  }
  return s;
}

// ---- rollout ---------------------------------------------------------------------------------

template <int D>
Rollout<D> RollOut(const std::function<Vec<D>(const Vec<D>&)>& velocity, const Vec<D>& start,
                   const Vec<D>& goal, const RolloutSettings& settings) {
  FS_THROW_UNLESS(std::isfinite(settings.dt) && settings.dt > 0, "rollout: dt ", settings.dt,
                  " must be positive and finite");
  FS_THROW_UNLESS(std::isfinite(settings.max_step_length) && settings.max_step_length >= 0,
                  "rollout: max_step_length ", settings.max_step_length,
                  " must be finite and non-negative");
  FS_THROW_UNLESS(settings.max_steps >= 0, "rollout: max_steps ", settings.max_steps,
                  " must be non-negative");
  FS_THROW_UNLESS(std::isfinite(settings.goal_tolerance) && settings.goal_tolerance >= 0,
                  "rollout: goal_tolerance ", settings.goal_tolerance,
                  " must be finite and non-negative");
  FS_THROW_UNLESS(start.allFinite() && goal.allFinite(), "rollout: start (", start.transpose(),
                  ") or goal (", goal.transpose(), ") is not finite");
  std::vector<Vec<D>> path{start};
  Rollout<D> out;
  Vec<D> y = start;
  for (int k = 0;; ++k) {
    if ((y - goal).norm() <= settings.goal_tolerance) {
      out.reached = true;
      break;
    }
    if (k == settings.max_steps) break;
    const Vec<D> v = velocity(y);
    if (!v.allFinite()) {
      out.finite = false;
      break;
    }
    Vec<D> step = settings.dt * v;
    const double length = step.norm();
    if (settings.max_step_length > 0 && length > settings.max_step_length)
      step *= settings.max_step_length / length;
    y += step;
    path.push_back(y);
  }
  out.path.resize(D, static_cast<Eigen::Index>(path.size()));
  for (std::size_t i = 0; i < path.size(); ++i)
    out.path.col(static_cast<Eigen::Index>(i)) = path[i];
  return out;
}

#define FORESIGHT_INSTANTIATE_TRANSFORMS(D)                                                       \
  template class ObstacleTransform<D>;                                                            \
  template class ComposedSystem<D>;                                                               \
  template RbfFlow<D> FitBiasTransform<D>(const RbfGrid<D>&, const Eigen::Matrix<double, D, -1>&, \
                                          const Vec<D>&, double, FlowSettings<D>);                \
  template Rollout<D> RollOut<D>(const std::function<Vec<D>(const Vec<D>&)>&, const Vec<D>&,      \
                                 const Vec<D>&, const RolloutSettings&);
FORESIGHT_INSTANTIATE_TRANSFORMS(2)
FORESIGHT_INSTANTIATE_TRANSFORMS(3)
#undef FORESIGHT_INSTANTIATE_TRANSFORMS

}  // namespace foresight::imitation
