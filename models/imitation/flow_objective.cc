#include "models/imitation/flow_objective.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "core/error.h"

namespace foresight::imitation {
namespace {

/// Samples per chunk: the unit of work of a thread and of the ordered gradient sum.
constexpr int kChunk = 8;

/// Runs body(chunk) for chunk in [0, chunks) on up to `threads` threads (chunk c on thread c % T).
template <typename Body>
void ForChunks(int chunks, int threads, const Body& body) {
  const int t = std::max(1, std::min(threads, chunks));
  if (t == 1) {
    for (int c = 0; c < chunks; ++c) body(c);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(t - 1));
  for (int i = 1; i < t; ++i)
    pool.emplace_back([&, i] {
      for (int c = i; c < chunks; c += t) body(c);
    });
  for (int c = 0; c < chunks; c += t) body(c);
  for (std::thread& th : pool) th.join();
}

template <int D>
class RbfFlowObjective final : public FlowObjective {
 public:
  using V = Vec<D>;
  using M = Mat<D>;

  RbfFlowObjective(const RbfGridSpec<D>& spec, double time, int steps, int segments, double kappa,
                   double goal_epsilon)
      : grid_(spec, "flow objective grid"),
        h_(time / steps),
        steps_(steps),
        segments_(segments),
        kappa_(kappa),
        eps2_(goal_epsilon * goal_epsilon) {
    FS_THROW_UNLESS(std::isfinite(time) && time > 0, "flow objective: time must be > 0, got ",
                    time);
    FS_THROW_UNLESS(steps >= 1, "flow objective: steps must be >= 1, got ", steps);
    FS_THROW_UNLESS(segments >= 1 && segments <= steps, "flow objective: segments must be in [1, ",
                    steps, "], got ", segments);
    FS_THROW_UNLESS(std::isfinite(kappa) && kappa >= 0, "flow objective: kappa must be >= 0, got ",
                    kappa);
    FS_THROW_UNLESS(std::isfinite(goal_epsilon) && goal_epsilon > 0,
                    "flow objective: goal_epsilon must be > 0, got ", goal_epsilon);
  }

  int dimension() const override { return D; }
  int num_centres() const override { return grid_.size(); }
  int segments() const override { return segments_; }
  int steps() const override { return steps_; }
  double time() const override { return h_ * steps_; }
  double gamma() const override { return grid_.gamma(); }
  double cutoff_radius() const override { return grid_.spec().cutoff_radius; }
  void Centre(int t, double* out) const override {
    const V c = grid_.Centre(t);
    for (int a = 0; a < D; ++a) out[a] = c[a];
  }

  double Evaluate(const double* weights, double log_speed, const FlowObjectiveBatch& b, int threads,
                  double* grad_weights, double* grad_log_speed) const override;

 private:
  /// The rows of segment g(k) = floor(k S / K) of W [S m, d].
  const double* StepWeights(const double* w, int k) const {
    return w + static_cast<std::ptrdiff_t>(k * segments_ / steps_) * grid_.size() * D;
  }
  /// Features at s and A = DV(s) (V into *v when not null).
  void Field(const double* w, const V& s, RbfFeatures<D>* f, V* v, M* a) const {
    grid_.Evaluate(s, f);
    const double g2 = -2 * grid_.gamma();
    if (v != nullptr) v->setZero();
    a->setZero();
    for (int i = 0; i < f->count; ++i) {
      const Eigen::Map<const V> wt(w + static_cast<std::ptrdiff_t>(f->index[i]) * D);
      if (v != nullptr) *v += f->phi[i] * wt;
      a->noalias() += wt * (g2 * f->phi[i] * f->offset[i]).transpose();
    }
  }
  /// The penalty term max(0, h ||A||_F - kappa)^2 and, when grad is not null, its derivative in A
  /// times `coefficient` added to *grad.
  double Penalty(const M& a, double coefficient, M* grad) const {
    const double norm = std::sqrt(a.squaredNorm() + 1e-30);  // as flow_net.h
    const double e = h_ * norm - kappa_;
    if (e <= 0) return 0;
    if (grad != nullptr) *grad += (coefficient * 2 * e * h_ / norm) * a;
    return e * e;
  }
  /// Euler integration of one sample: s[0..K] and, when j is not null, J[0..K]; returns the sum
  /// over steps of the penalty term when `penalised`.
  double Forward(const double* w, const V& x, bool penalised, RbfFeatures<D>* f, V* s, M* j) const {
    s[0] = x;
    if (j != nullptr) j[0].setIdentity();
    double penalty = 0;
    V v;
    M a;
    for (int k = 0; k < steps_; ++k) {
      Field(StepWeights(w, k), s[k], f, &v, &a);
      if (penalised) penalty += Penalty(a, 0, nullptr);
      if (j != nullptr) j[k + 1] = j[k] + h_ * (a * j[k]);
      s[k + 1] = s[k] + h_ * v;
    }
    return penalty;
  }
  /// The reverse pass of one sample (file comment), adding dL/dW into gw [S m, d].
  void Backward(const double* w, const V* s, const M* j, V gs, M gj, double penalty_coefficient,
                RbfFeatures<D>* f, double* gw) const {
    const double g = grid_.gamma(), g2 = -2 * g;
    M a, ga;
    for (int k = steps_ - 1; k >= 0; --k) {
      const double* wk = StepWeights(w, k);
      double* gwk = gw + (wk - w);
      Field(wk, s[k], f, nullptr, &a);
      ga.setZero();
      if (j != nullptr) ga.noalias() += h_ * (gj * j[k].transpose());
      if (penalty_coefficient > 0) Penalty(a, penalty_coefficient, &ga);
      V gs_next = gs + h_ * (a.transpose() * gs);
      for (int i = 0; i < f->count; ++i) {
        const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(f->index[i]) * D;
        const Eigen::Map<const V> wt(wk + row);
        Eigen::Map<V> gwt(gwk + row);
        const double phi = f->phi[i];
        const V& r = f->offset[i];
        const V dphi = g2 * phi * r;
        gwt += h_ * phi * gs + ga * dphi;
        const V u = ga.transpose() * wt;
        // H_t u = phi (4 g^2 r (r . u) - 2 g u)
        gs_next += phi * (4 * g * g * r.dot(u) * r - 2 * g * u);
      }
      if (j != nullptr) gj += h_ * (a.transpose() * gj);
      gs = gs_next;
    }
  }

  RbfGrid<D> grid_;
  double h_;
  int steps_, segments_;
  double kappa_, eps2_;
};

template <int D>
double RbfFlowObjective<D>::Evaluate(const double* weights, double log_speed,
                                     const FlowObjectiveBatch& b, int threads, double* grad_weights,
                                     double* grad_log_speed) const {
  FS_THROW_UNLESS(weights != nullptr && b.x != nullptr && b.v != nullptr && b.goal != nullptr,
                  "flow objective: null weights, positions, velocities or goal");
  FS_THROW_UNLESS(b.batch >= 1, "flow objective: the batch must hold >= 1 sample, got ", b.batch);
  FS_THROW_UNLESS(b.penalty_count >= 0 && (b.penalty_count == 0 || b.penalty != nullptr),
                  "flow objective: ", b.penalty_count, " penalty points without data");
  FS_THROW_UNLESS(std::isfinite(b.penalty_weight) && b.penalty_weight >= 0,
                  "flow objective: penalty weight must be finite and >= 0, got ", b.penalty_weight);
  FS_THROW_UNLESS(std::isfinite(log_speed), "flow objective: log_speed is not finite");
  FS_THROW_UNLESS((grad_weights == nullptr) == (grad_log_speed == nullptr),
                  "flow objective: ask for both gradients or neither");
  const bool penalised = b.penalty_weight > 0;
  const int nb = b.batch, nr = penalised ? b.penalty_count : 0;
  const int n = nb + nr + 1;  // velocity samples, penalty points, the goal (last)
  const int k1 = steps_ + 1;
  std::vector<V> s(static_cast<std::size_t>(n) * k1);
  std::vector<M> jac(static_cast<std::size_t>(nb) * k1);
  std::vector<double> penalty(static_cast<std::size_t>(n), 0.0);
  const auto point = [&](int i) -> V {
    if (i < nb) return Eigen::Map<const V>(b.x + static_cast<std::ptrdiff_t>(i) * D);
    if (i < nb + nr)
      return Eigen::Map<const V>(b.penalty + static_cast<std::ptrdiff_t>(i - nb) * D);
    return Eigen::Map<const V>(b.goal);
  };
  const int chunks = (n + kChunk - 1) / kChunk;
  ForChunks(chunks, threads, [&](int c) {
    auto f = std::make_unique<RbfFeatures<D>>();
    for (int i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i)
      penalty[static_cast<std::size_t>(i)] =
          Forward(weights, point(i), penalised && i < nb + nr, f.get(),
                  &s[static_cast<std::size_t>(i) * k1],
                  i < nb ? &jac[static_cast<std::size_t>(i) * k1] : nullptr);
  });

  // The velocity loss and its adjoints at z = s_K, J = J_K and z_e (serial: cheap, ordered).
  const double speed = std::exp(log_speed);
  const V ze = s[static_cast<std::size_t>(n - 1) * k1 + steps_];
  std::vector<V> gz(static_cast<std::size_t>(nb));
  std::vector<M> gjac(static_cast<std::size_t>(nb));
  V gze = V::Zero();
  double loss = 0, gls = 0;
  for (int i = 0; i < nb; ++i) {
    const std::size_t last = static_cast<std::size_t>(i) * k1 + steps_;
    const V u = s[last] - ze;
    const double norm = std::sqrt(u.squaredNorm() + eps2_);
    const V grad_phi = u / norm;
    const M inverse = jac[last].inverse();
    const V y = inverse * grad_phi;
    const V target = Eigen::Map<const V>(b.v + static_cast<std::ptrdiff_t>(i) * D);
    const V r = -speed * y - target;
    loss += r.squaredNorm();
    const V gf = (2.0 / nb) * r;  // dL/df
    gls += speed * gf.dot(-y);
    const V gy = -speed * gf;
    const V gg = inverse.transpose() * gy;
    gjac[static_cast<std::size_t>(i)] = -gg * y.transpose();
    const V gu = (gg - grad_phi * grad_phi.dot(gg)) / norm;
    gz[static_cast<std::size_t>(i)] = gu;
    gze -= gu;
  }
  loss /= nb;
  double penalty_sum = 0;
  for (double p : penalty) penalty_sum += p;
  const double penalty_coefficient =
      penalised ? b.penalty_weight / (static_cast<double>(steps_) * (nb + nr)) : 0.0;
  loss += penalty_coefficient * penalty_sum;
  if (grad_weights == nullptr) return loss;

  const std::size_t size = static_cast<std::size_t>(segments_) * grid_.size() * D;
  std::vector<double> partial(static_cast<std::size_t>(chunks) * size, 0.0);
  ForChunks(chunks, threads, [&](int c) {
    auto f = std::make_unique<RbfFeatures<D>>();
    double* gw = &partial[static_cast<std::size_t>(c) * size];
    for (int i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      const V* si = &s[static_cast<std::size_t>(i) * k1];
      const double pc = i < nb + nr ? penalty_coefficient : 0.0;
      if (i < nb)
        Backward(weights, si, &jac[static_cast<std::size_t>(i) * k1],
                 gz[static_cast<std::size_t>(i)], gjac[static_cast<std::size_t>(i)], pc, f.get(),
                 gw);
      else
        Backward(weights, si, nullptr, i == n - 1 ? gze : V::Zero(), M::Zero(), pc, f.get(), gw);
    }
  });
  std::fill(grad_weights, grad_weights + size, 0.0);
  for (int c = 0; c < chunks; ++c) {
    const double* gw = &partial[static_cast<std::size_t>(c) * size];
    for (std::size_t e = 0; e < size; ++e) grad_weights[e] += gw[e];
  }
  *grad_log_speed = gls;
  return loss;
}

}  // namespace

template <int D>
std::shared_ptr<const FlowObjective> MakeFlowObjective(const RbfGridSpec<D>& grid, double time,
                                                       int steps, int segments, double kappa,
                                                       double goal_epsilon) {
  return std::make_shared<RbfFlowObjective<D>>(grid, time, steps, segments, kappa, goal_epsilon);
}

template std::shared_ptr<const FlowObjective> MakeFlowObjective<2>(const RbfGridSpec<2>&, double,
                                                                   int, int, double, double);
template std::shared_ptr<const FlowObjective> MakeFlowObjective<3>(const RbfGridSpec<3>&, double,
                                                                   int, int, double, double);

}  // namespace foresight::imitation
