#include "inference/constrained/collision_cost.h"

#include <cmath>
#include <utility>

#include "core/error.h"

namespace foresight::constrained {

namespace {
/// The Gauss-Hermite points dropped from every operator's rule weigh at most this much together.
constexpr double kMaxDroppedMass = 1e-6;
}  // namespace

Eigen::VectorXd RuleTimes(TimeRule rule, double horizon, int k) {
  FS_THROW_UNLESS(k >= 1, "RuleTimes: need >= 1 time point, got ", k);
  FS_THROW_UNLESS(std::isfinite(horizon) && horizon > 0, "RuleTimes: horizon must be > 0, got ",
                  horizon);
  const double h = horizon / k, shift = rule == TimeRule::kMidpoint ? 0.5 : 0.0;
  Eigen::VectorXd t(k);
  for (int i = 0; i < k; ++i) t[i] = (i + 1 - shift) * h;
  return t;
}

CollisionCost::CollisionCost(const occupancy::Map* map, const TimeBasis& basis,
                             Eigen::VectorXd times, int order)
    : map_(map), basis_(basis), times_(std::move(times)), order_(order) {
  FS_THROW_UNLESS(map_ != nullptr, "CollisionCost: map is null");
  FS_THROW_UNLESS(basis_.size() >= 1, "CollisionCost: basis has no centres");
  FS_THROW_UNLESS(times_.size() >= 1, "CollisionCost: times is empty (need >= 1 time point)");
  for (Eigen::Index k = 0; k < times_.size(); ++k) {
    FS_THROW_UNLESS(std::isfinite(times_[k]), "CollisionCost: times[", k, "] is not finite (",
                    times_[k], ")");
  }
  FS_THROW_UNLESS(order_ >= 1 && order_ <= 64,
                  "CollisionCost: order (Gauss-Hermite points per axis) must be in [1, 64], got ",
                  order_);
  phi_ = basis_.Design(times_);
  // The lightest points dropped in whole symmetry orbits, at most 1e-6 of mass together: C (an
  // expectation of p in [0, 1]) changes by at most 1e-6 (a thousandth of the 1e-3 asked of it),
  // while order 24 evaluates about 200 of its 576 points (336 when only weights below 1e-12 were
  // dropped).
  rule_ = PrunedRuleByMass(order_, kMaxDroppedMass);
}

CollisionCost::Workspace CollisionCost::MakeWorkspace() const {
  Workspace ws;
  ws.map = map_->MakeWorkspace();
  ws.batch.Resize(rule_.size());
  ws.points.resize(2, rule_.size());
  return ws;
}

namespace {

void CheckComponent(const ComponentParams& c, int basis) {
  FS_THROW_UNLESS(c.mean.rows() == basis && c.mean.cols() == 2, "CollisionCost: component mean is ",
                  c.mean.rows(), " x ", c.mean.cols(), ", the basis needs ", basis, " x 2");
  FS_THROW_UNLESS(c.log_u.size() == basis, "CollisionCost: component log_u has ", c.log_u.size(),
                  " entries, the basis has ", basis);
}

void CheckOffset(const Eigen::Matrix2Xd& offset, Eigen::Index times) {
  FS_THROW_UNLESS(offset.cols() == 0 || offset.cols() == times, "CollisionCost: offset is 2 x ",
                  offset.cols(), ", expected 2 x ", times, " (one column per time) or empty");
}

}  // namespace

double CollisionCost::Component(const ComponentParams& c, Workspace* ws,
                                ComponentGradient* gradient) const {
  const int m = basis();
  CheckComponent(c, m);
  FS_THROW_UNLESS(ws != nullptr, "CollisionCost::Component: workspace is null");
  CheckOffset(ws->offset, times_.size());
  const bool has_offset = ws->offset.cols() != 0;
  const int nq = rule_.size();
  if (ws->points.cols() != nq) ws->points.resize(2, nq);
  if (ws->batch.probability.size() != nq) ws->batch.Resize(nq);
  if (gradient != nullptr) {
    if (gradient->mean.rows() != m || gradient->mean.cols() != 2 || gradient->log_u.size() != m)
      gradient->Resize(m);
    gradient->mean.setZero();
    gradient->log_u.setZero();
    gradient->chol_v.setZero();
  }
  const Eigen::Matrix2d& L = c.chol_v;
  double total = 0;
  for (Eigen::Index k = 0; k < times_.size(); ++k) {
    // mu = M' phi(t_k), s^2 = phi' U phi with U = diag(exp(log_u)) (thesis eq. GPdef_eq_ch5).
    Eigen::Vector2d mu = Eigen::Vector2d::Zero();
    double s2 = 0;
    for (int j = 0; j < m; ++j) {
      const double p = phi_(k, j);
      mu[0] += c.mean(j, 0) * p;
      mu[1] += c.mean(j, 1) * p;
      s2 += std::exp(c.log_u[j]) * p * p;
    }
    if (has_offset) mu += ws->offset.col(k);
    const double s = std::sqrt(s2);
    // Change of variables through the Cholesky factor: x_q = mu + s L_V z_q.
    const Eigen::Matrix2d A = s * L;
    ws->points.noalias() = A * rule_.points;
    ws->points.colwise() += mu;
    if (gradient == nullptr) {  // the value alone: no gradients of the map are computed
      map_->ProbabilityBatch(ws->points, &ws->map, ws->batch.probability);
      total += rule_.weights.dot(ws->batch.probability);
      continue;
    }
    map_->QueryBatch(ws->points, &ws->map, &ws->batch);
    total += rule_.weights.dot(ws->batch.probability);
    Eigen::Vector2d g_sum = Eigen::Vector2d::Zero();  // sum_q beta_q g_q
    Eigen::Matrix2d gz = Eigen::Matrix2d::Zero();     // sum_q beta_q g_q z_q'
    for (int q = 0; q < nq; ++q) {
      const double b = rule_.weights[q];
      const double gx = ws->batch.gradient(0, q), gy = ws->batch.gradient(1, q);
      const double zx = rule_.points(0, q), zy = rule_.points(1, q);
      g_sum[0] += b * gx;
      g_sum[1] += b * gy;
      gz(0, 0) += b * gx * zx;
      gz(0, 1) += b * gx * zy;
      gz(1, 0) += b * gy * zx;
      gz(1, 1) += b * gy * zy;
    }
    for (int j = 0; j < m; ++j) {
      gradient->mean(j, 0) += phi_(k, j) * g_sum[0];
      gradient->mean(j, 1) += phi_(k, j) * g_sum[1];
    }
    gradient->chol_v(0, 0) += s * gz(0, 0);
    gradient->chol_v(1, 0) += s * gz(1, 0);
    gradient->chol_v(1, 1) += s * gz(1, 1);
    // sum_q beta_q g_q' L z_q = tr(L' gz); ds/dlog_u_j = u_j phi_j^2 / (2 s) (skip s = 0, where
    // every phi_j has underflowed and the derivative vanishes).
    if (s > 0) {
      const double h = (L.transpose() * gz).trace();
      for (int j = 0; j < m; ++j) {
        const double p = phi_(k, j);
        gradient->log_u[j] += h * std::exp(c.log_u[j]) * p * p / (2 * s);
      }
    }
  }
  const double inv_k = 1.0 / static_cast<double>(times_.size());
  if (gradient != nullptr) {
    gradient->mean *= inv_k;
    gradient->log_u *= inv_k;
    gradient->chol_v *= inv_k;
  }
  return total * inv_k;
}

double CollisionCost::Mixture(const std::vector<double>& alpha,
                              const std::vector<ComponentParams>& components, Workspace* ws) const {
  FS_THROW_UNLESS(alpha.size() == components.size(), "CollisionCost::Mixture: ", alpha.size(),
                  " weights for ", components.size(), " components");
  double total = 0;
  for (std::size_t r = 0; r < components.size(); ++r) {
    FS_THROW_UNLESS(std::isfinite(alpha[r]), "CollisionCost::Mixture: alpha[", r,
                    "] is not finite (", alpha[r], ")");
    total += alpha[r] * Component(components[r], ws, nullptr);
  }
  return total;
}

Eigen::Matrix2Xd CollisionCost::Abscissae(const ComponentParams& c,
                                          const Eigen::Matrix2Xd& offset) const {
  const int m = basis();
  CheckComponent(c, m);
  CheckOffset(offset, times_.size());
  const int nq = rule_.size();
  const Eigen::VectorXd u = c.log_u.array().exp();
  Eigen::Matrix2Xd out(2, times_.size() * nq);
  for (Eigen::Index k = 0; k < times_.size(); ++k) {
    const Eigen::VectorXd phi = phi_.row(k).transpose();
    Eigen::Vector2d mu = c.mean.transpose() * phi;
    if (offset.cols() != 0) mu += offset.col(k);
    const double s = std::sqrt(phi.cwiseAbs2().dot(u));
    out.middleCols(k * nq, nq) = (s * c.chol_v * rule_.points).colwise() + mu;
  }
  return out;
}

}  // namespace foresight::constrained
