#include "models/imitation/flow_net.h"

#include <cmath>
#include <vector>

#include "core/error.h"

namespace foresight::imitation {

namespace {

bool AllFinite(const torch::Tensor& t) { return torch::isfinite(t).all().item<bool>(); }

/// A loss whose gradients were computed beside it (flow_objective.h): backward scales them by the
/// incoming gradient.
struct PrecomputedLoss : public torch::autograd::Function<PrecomputedLoss> {
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& weights,
                               const torch::Tensor& log_speed, const torch::Tensor& loss,
                               const torch::Tensor& grad_weights,
                               const torch::Tensor& grad_log_speed) {
    (void)weights, (void)log_speed;
    ctx->save_for_backward({grad_weights, grad_log_speed});
    return loss.clone();
  }
  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grad_output) {
    const auto saved = ctx->get_saved_variables();
    const torch::Tensor g = grad_output[0];
    return {saved[0] * g, saved[1] * g, torch::Tensor(), torch::Tensor(), torch::Tensor()};
  }
};

/// [n, d] float64 contiguous (a view when it already is).
torch::Tensor Contiguous64(const torch::Tensor& t) {
  return t.detach().to(torch::kFloat64).contiguous();
}

}  // namespace

torch::Tensor NaturalGradientVelocity(const torch::Tensor& z, const torch::Tensor& jacobian,
                                      const torch::Tensor& goal_image, const torch::Tensor& speed) {
  const torch::Tensor diff = z - goal_image.unsqueeze(0);  // [B, d]
  const torch::Tensor norm =
      torch::sqrt(diff.square().sum(1, /*keepdim=*/true) + kGoalEpsilon * kGoalEpsilon);
  const torch::Tensor grad = (diff / norm).unsqueeze(2);  // [B, d, 1]
  return -speed * torch::linalg::solve(jacobian, grad, /*left=*/true).squeeze(2);
}

RbfFlowNetImpl::RbfFlowNetImpl(const torch::Tensor& centres, double gamma, double cutoff_radius,
                               double time, int steps, double initial_speed, int segments)
    : gamma_(gamma),
      cutoff_radius_(cutoff_radius),
      time_(time),
      steps_(steps),
      segments_(segments) {
  FS_THROW_UNLESS(centres.dim() == 2 && centres.size(0) >= 1 && centres.size(1) >= 1,
                  "RbfFlowNet: centres must be [m, d] with m, d >= 1, got ", centres.sizes());
  FS_THROW_UNLESS(std::isfinite(gamma) && gamma > 0, "RbfFlowNet: gamma must be > 0, got ", gamma);
  FS_THROW_UNLESS(std::isfinite(cutoff_radius) && cutoff_radius > 0,
                  "RbfFlowNet: cutoff_radius must be > 0, got ", cutoff_radius);
  FS_THROW_UNLESS(std::isfinite(time) && time > 0, "RbfFlowNet: time must be > 0, got ", time);
  FS_THROW_UNLESS(steps >= 1, "RbfFlowNet: steps must be >= 1, got ", steps);
  FS_THROW_UNLESS(segments >= 1 && segments <= steps,
                  "RbfFlowNet: segments must be in [1, steps = ", steps, "], got ", segments);
  FS_THROW_UNLESS(std::isfinite(initial_speed) && initial_speed > 0,
                  "RbfFlowNet: initial_speed must be > 0, got ", initial_speed);
  const torch::Tensor c = centres.detach().to(torch::kFloat64).contiguous().clone();
  FS_THROW_UNLESS(AllFinite(c), "RbfFlowNet: centres contain a non-finite value");
  centres_ = register_buffer("centres", c);
  weights = register_parameter("weights", torch::zeros({segments * c.size(0), c.size(1)}, kDouble));
  log_speed = register_parameter("log_speed", torch::full({}, std::log(initial_speed), kDouble));
}

void RbfFlowNetImpl::CheckPoints(const torch::Tensor& x, const char* what) const {
  FS_THROW_UNLESS(x.dim() == 2 && x.size(1) == centres_.size(1), "RbfFlowNet: ", what,
                  " must be [B, ", centres_.size(1), "], got ", x.sizes());
  FS_THROW_UNLESS(x.scalar_type() == torch::kFloat64, "RbfFlowNet: ", what,
                  " must be kFloat64, got ", x.scalar_type());
}

std::pair<torch::Tensor, torch::Tensor> RbfFlowNetImpl::Features(const torch::Tensor& s) const {
  const torch::Tensor offset = s.unsqueeze(1) - centres_.unsqueeze(0);  // [B, m, d]
  const torch::Tensor d2 = offset.square().sum(2);                      // [B, m]
  // The mask is a constant of the graph: the truncated features and their derivatives are 0.
  const torch::Tensor inside = (d2 <= cutoff_radius_ * cutoff_radius_).to(torch::kFloat64);
  return {torch::exp(-gamma_ * d2) * inside, offset};
}

torch::Tensor RbfFlowNetImpl::SegmentWeights(int segment) const {
  const std::int64_t m = centres_.size(0);
  return weights.narrow(0, segment * m, m);
}

torch::Tensor RbfFlowNetImpl::StepWeights(int k) const {
  return SegmentWeights(static_cast<int>(static_cast<std::int64_t>(k) * segments_ / steps_));
}

std::pair<torch::Tensor, torch::Tensor> RbfFlowNetImpl::Field(const torch::Tensor& s, int segment) {
  CheckPoints(s, "s");
  FS_THROW_UNLESS(segment >= 0 && segment < segments_, "RbfFlowNet: segment ", segment,
                  " is outside [0, ", segments_, ")");
  const torch::Tensor w = SegmentWeights(segment);
  auto [phi, offset] = Features(s);
  const torch::Tensor v = torch::matmul(phi, w);  // [B, d]
  // d phi_t/ds = -2 gamma phi_t (s - c_t): [B, m, d]; DV = W' dphi/ds: [d, m] x [B, m, d].
  const torch::Tensor dphi = (-2 * gamma_) * phi.unsqueeze(2) * offset;
  return {v, torch::matmul(w.t(), dphi)};
}

torch::Tensor RbfFlowNetImpl::Integrate(const torch::Tensor& x, torch::Tensor* jacobian) {
  const double h = time_ / steps_;
  const std::int64_t b = x.size(0), d = x.size(1);
  torch::Tensor s = x;
  torch::Tensor j;
  if (jacobian) j = torch::eye(d, kDouble).expand({b, d, d});
  for (int k = 0; k < steps_; ++k) {
    const torch::Tensor w = StepWeights(k);
    auto [phi, offset] = Features(s);
    if (jacobian) {
      const torch::Tensor dphi = (-2 * gamma_) * phi.unsqueeze(2) * offset;
      const torch::Tensor dv = torch::matmul(w.t(), dphi);  // [B, d, d]
      j = j + h * torch::matmul(dv, j);
    }
    s = s + h * torch::matmul(phi, w);
  }
  if (jacobian) *jacobian = j;
  return s;
}

std::pair<torch::Tensor, torch::Tensor> RbfFlowNetImpl::Forward(const torch::Tensor& x) {
  CheckPoints(x, "x");
  torch::Tensor j;
  torch::Tensor z = Integrate(x, &j);
  return {z, j};
}

torch::Tensor RbfFlowNetImpl::Map(const torch::Tensor& x) {
  CheckPoints(x, "x");
  return Integrate(x, nullptr);
}

torch::Tensor RbfFlowNetImpl::Velocity(const torch::Tensor& x, const torch::Tensor& goal) {
  CheckPoints(x, "x");
  FS_THROW_UNLESS(goal.dim() == 1 && goal.size(0) == centres_.size(1), "RbfFlowNet: goal must be [",
                  centres_.size(1), "], got ", goal.sizes());
  // One pass over [x; goal]: z_e is computed by the very same operations as psi(x).
  const std::int64_t b = x.size(0);
  torch::Tensor j;
  const torch::Tensor z = Integrate(torch::cat({x, goal.to(torch::kFloat64).unsqueeze(0)}), &j);
  return NaturalGradientVelocity(z.narrow(0, 0, b), j.narrow(0, 0, b), z[b], torch::exp(log_speed));
}

torch::Tensor RbfFlowNetImpl::InvertibilityPenalty(const torch::Tensor& x) {
  CheckPoints(x, "x");
  const double h = time_ / steps_;
  torch::Tensor s = x;
  torch::Tensor total = torch::zeros({}, x.options());
  for (int k = 0; k < steps_; ++k) {
    const torch::Tensor w = StepWeights(k);
    auto [phi, offset] = Features(s);
    const torch::Tensor dphi = (-2 * gamma_) * phi.unsqueeze(2) * offset;
    const torch::Tensor dv = torch::matmul(w.t(), dphi);  // [B, d, d]
    const torch::Tensor norm = torch::sqrt(dv.square().sum({1, 2}) + 1e-30);
    total = total + torch::relu(h * norm - kStepLipschitz).square().mean();
    s = s + h * torch::matmul(phi, w);
  }
  return total / steps_;
}

void RbfFlowNetImpl::SetObjective(std::shared_ptr<const FlowObjective> objective) {
  if (objective != nullptr) {
    FS_THROW_UNLESS(
        objective->dimension() == dimension() && objective->num_centres() == num_centres() &&
            objective->segments() == segments_,
        "RbfFlowNet: the objective is for ", objective->num_centres(), " centres in ",
        objective->dimension(), "-D with ", objective->segments(), " segment(s), the net has ",
        num_centres(), " in ", dimension(), "-D with ", segments_);
    FS_THROW_UNLESS(
        objective->steps() == steps_ && std::abs(objective->time() - time_) <= 1e-12 * time_ &&
            objective->gamma() == gamma_ && objective->cutoff_radius() == cutoff_radius_,
        "RbfFlowNet: the objective's time ", objective->time(), ", steps ", objective->steps(),
        ", gamma ", objective->gamma(), " and cut-off ", objective->cutoff_radius(),
        " differ from the net's ", time_, ", ", steps_, ", ", gamma_, ", ", cutoff_radius_);
    const torch::Tensor c = centres_.contiguous();
    const double* cp = c.data_ptr<double>();
    std::vector<double> centre(static_cast<std::size_t>(dimension()));
    for (int t = 0; t < num_centres(); ++t) {
      objective->Centre(t, centre.data());
      for (int a = 0; a < dimension(); ++a)
        FS_THROW_UNLESS(
            std::abs(centre[static_cast<std::size_t>(a)] - cp[t * dimension() + a]) <= 1e-9,
            "RbfFlowNet: the objective's inducing state ", t, " is not the net's");
    }
  }
  objective_ = std::move(objective);
}

torch::Tensor RbfFlowNetImpl::ObjectiveLoss(const torch::Tensor& x, const torch::Tensor& v,
                                            const torch::Tensor& goal,
                                            const torch::Tensor& penalty_points,
                                            double penalty_weight, bool with_gradient) {
  if (objective_ == nullptr) return {};
  CheckPoints(x, "x");
  FS_THROW_UNLESS(v.sizes() == x.sizes(), "RbfFlowNet: velocities ", v.sizes(), " and positions ",
                  x.sizes(), " must be the same [B, d]");
  FS_THROW_UNLESS(goal.dim() == 1 && goal.size(0) == centres_.size(1), "RbfFlowNet: goal must be [",
                  centres_.size(1), "], got ", goal.sizes());
  const torch::Tensor xs = Contiguous64(x), vs = Contiguous64(v), gs = Contiguous64(goal);
  torch::Tensor ps;
  if (penalty_points.defined() && penalty_points.numel() > 0) {
    CheckPoints(penalty_points, "penalty points");
    ps = Contiguous64(penalty_points);
  }
  FlowObjectiveBatch batch;
  batch.x = xs.data_ptr<double>();
  batch.v = vs.data_ptr<double>();
  batch.batch = static_cast<int>(xs.size(0));
  batch.goal = gs.data_ptr<double>();
  batch.penalty = ps.defined() ? ps.data_ptr<double>() : nullptr;
  batch.penalty_count = ps.defined() ? static_cast<int>(ps.size(0)) : 0;
  batch.penalty_weight = penalty_weight;
  const torch::Tensor w = weights.detach().contiguous();
  const double ls = log_speed.item<double>();
  const int threads = std::max(1, torch::get_num_threads());
  if (!with_gradient)
    return torch::scalar_tensor(
        objective_->Evaluate(w.data_ptr<double>(), ls, batch, threads, nullptr, nullptr), kDouble);
  torch::Tensor grad_w = torch::empty_like(w);
  double grad_ls = 0;
  const double loss = objective_->Evaluate(w.data_ptr<double>(), ls, batch, threads,
                                           grad_w.data_ptr<double>(), &grad_ls);
  return PrecomputedLoss::apply(weights, log_speed, torch::scalar_tensor(loss, kDouble), grad_w,
                                torch::scalar_tensor(grad_ls, kDouble));
}

Eigen::MatrixXd RbfFlowNetImpl::WeightsAsEigen() const {
  const torch::Tensor w = weights.detach().contiguous();
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      w.data_ptr<double>(), w.size(0), w.size(1));
}

double RbfFlowNetImpl::speed() const { return std::exp(log_speed.item<double>()); }

torch::Tensor VelocityLoss(const torch::Tensor& predicted, const torch::Tensor& target) {
  FS_THROW_UNLESS(predicted.dim() == 2 && predicted.sizes() == target.sizes(),
                  "VelocityLoss: predicted ", predicted.sizes(), " and target ", target.sizes(),
                  " must be the same [B, d]");
  return (predicted - target).square().sum(1).mean();
}

}  // namespace foresight::imitation
