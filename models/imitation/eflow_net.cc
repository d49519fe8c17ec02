#include "models/imitation/eflow_net.h"

#include <cmath>
#include <random>
#include <string>

#include "core/error.h"

namespace foresight::imitation {

namespace {

const auto kLong = torch::TensorOptions().dtype(torch::kInt64);

Eigen::VectorXd ToEigenVector(const torch::Tensor& t) {
  const torch::Tensor c = t.detach().contiguous();
  return Eigen::Map<const Eigen::VectorXd>(c.data_ptr<double>(), c.numel());
}

}  // namespace

EFlowNetImpl::EFlowNetImpl(const EFlowNetOptions& options) : options_(options) {
  const int d = options.dimension, f = options.features;
  FS_THROW_UNLESS(d >= 2 && d <= EFlowModel::kMaxDimension, "EFlowNet: dimension ", d,
                  " is outside [2, ", EFlowModel::kMaxDimension, "]");
  FS_THROW_UNLESS(options.layers >= 1, "EFlowNet: layers must be >= 1, got ", options.layers);
  FS_THROW_UNLESS(f >= 1, "EFlowNet: features must be >= 1, got ", f);
  FS_THROW_UNLESS(std::isfinite(options.bandwidth) && options.bandwidth > 0,
                  "EFlowNet: bandwidth must be > 0, got ", options.bandwidth);
  FS_THROW_UNLESS(std::isfinite(options.initial_speed) && options.initial_speed > 0,
                  "EFlowNet: initial_speed must be > 0, got ", options.initial_speed);
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, options.bandwidth);
  std::uniform_real_distribution<double> uniform(0.0, 2 * M_PI);
  for (int l = 0; l < options.layers; ++l) {
    Layer layer;
    layer.transformed = l % d;
    std::vector<std::int64_t> fixed;
    for (int j = 0; j < d; ++j)
      if (j != layer.transformed) fixed.push_back(j);
    layer.fixed = torch::tensor(fixed, kLong);
    layer.changed = torch::full({1}, layer.transformed, kLong);
    torch::Tensor omega = torch::empty({f, d - 1}, kDouble), phase = torch::empty({f}, kDouble);
    auto o = omega.accessor<double, 2>();
    auto p = phase.accessor<double, 1>();
    for (int k = 0; k < f; ++k) {
      for (int j = 0; j + 1 < d; ++j) o[k][j] = normal(rng);
      p[k] = uniform(rng);
    }
    const std::string n = std::to_string(l);
    layer.omega = register_buffer("omega" + n, omega);
    layer.phase = register_buffer("phase" + n, phase);
    layer.scale = register_parameter("scale" + n, torch::zeros({f}, kDouble));
    layer.translate = register_parameter("translate" + n, torch::zeros({f}, kDouble));
    layers_.push_back(std::move(layer));
  }
  log_speed =
      register_parameter("log_speed", torch::full({}, std::log(options.initial_speed), kDouble));
}

void EFlowNetImpl::CheckPoints(const torch::Tensor& x, const char* what) const {
  FS_THROW_UNLESS(x.dim() == 2 && x.size(1) == options_.dimension, "EFlowNet: ", what,
                  " must be [B, ", options_.dimension, "], got ", x.sizes());
  FS_THROW_UNLESS(x.scalar_type() == torch::kFloat64, "EFlowNet: ", what, " must be kFloat64, got ",
                  x.scalar_type());
}

const EFlowNetImpl::Layer& EFlowNetImpl::LayerAt(int l) const {
  FS_THROW_UNLESS(l >= 0 && l < num_layers(), "EFlowNet: layer ", l, " is outside [0, ",
                  num_layers(), ")");
  return layers_[l];
}

void EFlowNetImpl::Terms(const Layer& layer, const torch::Tensor& x, torch::Tensor* s,
                         torch::Tensor* t, torch::Tensor* ds, torch::Tensor* dt) const {
  const double norm = std::sqrt(2.0 / options_.features);
  const torch::Tensor arg =
      torch::matmul(x.index_select(1, layer.fixed), layer.omega.t()) + layer.phase;  // [B, F]
  const torch::Tensor r = norm * torch::cos(arg);
  *s = torch::matmul(r, layer.scale);
  *t = torch::matmul(r, layer.translate);
  if (ds) {
    const torch::Tensor g = -norm * torch::sin(arg);  // d r_k / d arg_k
    *ds = torch::matmul(g * layer.scale, layer.omega);
    *dt = torch::matmul(g * layer.translate, layer.omega);
  }
}

torch::Tensor EFlowNetImpl::Apply(const Layer& layer, const torch::Tensor& x,
                                  torch::Tensor* jacobian) const {
  torch::Tensor s, t, ds, dt;
  Terms(layer, x, &s, &t, jacobian ? &ds : nullptr, jacobian ? &dt : nullptr);
  const torch::Tensor es = torch::exp(s);                   // [B]
  const torch::Tensor xb = x.select(1, layer.transformed);  // [B]
  if (jacobian) {
    // Row b of the layer Jacobian: exp(s) at b, x_b exp(s) ds/du + dt/du at the fixed a.
    const torch::Tensor row_a = (xb * es).unsqueeze(1) * ds + dt;  // [B, d-1]
    const torch::Tensor row = torch::zeros_like(x)
                                  .index_copy(1, layer.fixed, row_a)
                                  .index_copy(1, layer.changed, es.unsqueeze(1));
    const torch::Tensor new_row = torch::matmul(row.unsqueeze(1), *jacobian);  // [B, 1, d]
    *jacobian = jacobian->index_copy(1, layer.changed, new_row);
  }
  return x.index_copy(1, layer.changed, (xb * es + t).unsqueeze(1));
}

torch::Tensor EFlowNetImpl::Propagate(const torch::Tensor& x, torch::Tensor* jacobian) const {
  const std::int64_t b = x.size(0), d = x.size(1);
  if (jacobian) *jacobian = torch::eye(d, kDouble).expand({b, d, d});
  torch::Tensor y = x;
  for (const Layer& layer : layers_) y = Apply(layer, y, jacobian);
  return y;
}

std::pair<torch::Tensor, torch::Tensor> EFlowNetImpl::Forward(const torch::Tensor& x) {
  CheckPoints(x, "x");
  torch::Tensor j;
  torch::Tensor z = Propagate(x, &j);
  return {z, j};
}

torch::Tensor EFlowNetImpl::Map(const torch::Tensor& x) {
  CheckPoints(x, "x");
  return Propagate(x, nullptr);
}

torch::Tensor EFlowNetImpl::ForwardLayer(int l, const torch::Tensor& x) {
  CheckPoints(x, "x");
  return Apply(LayerAt(l), x, nullptr);
}

torch::Tensor EFlowNetImpl::InverseLayer(int l, const torch::Tensor& y) {
  CheckPoints(y, "y");
  const Layer& layer = LayerAt(l);
  torch::Tensor s, t;
  Terms(layer, y, &s, &t, nullptr, nullptr);  // y_a = x_a
  const torch::Tensor xb = (y.select(1, layer.transformed) - t) * torch::exp(-s);
  return y.index_copy(1, layer.changed, xb.unsqueeze(1));
}

torch::Tensor EFlowNetImpl::Inverse(const torch::Tensor& z) {
  CheckPoints(z, "z");
  torch::Tensor x = z;
  for (int l = num_layers() - 1; l >= 0; --l) x = InverseLayer(l, x);
  return x;
}

torch::Tensor EFlowNetImpl::Velocity(const torch::Tensor& x, const torch::Tensor& goal) {
  CheckPoints(x, "x");
  FS_THROW_UNLESS(goal.dim() == 1 && goal.size(0) == options_.dimension, "EFlowNet: goal must be [",
                  options_.dimension, "], got ", goal.sizes());
  // One pass over [x; goal]: z_e is computed by the very same operations as psi(x).
  const std::int64_t b = x.size(0);
  torch::Tensor j;
  const torch::Tensor z = Propagate(torch::cat({x, goal.to(torch::kFloat64).unsqueeze(0)}), &j);
  return NaturalGradientVelocity(z.narrow(0, 0, b), j.narrow(0, 0, b), z[b], torch::exp(log_speed));
}

EFlowModel EFlowNetImpl::ToEngine(const Eigen::VectorXd& goal) const {
  std::vector<EFlowCouplingLayer> layers;
  for (const Layer& layer : layers_) {
    EFlowCouplingLayer e;
    e.transformed = layer.transformed;
    const torch::Tensor omega = layer.omega.detach().contiguous();
    e.omega =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            omega.data_ptr<double>(), omega.size(0), omega.size(1));
    e.phase = ToEigenVector(layer.phase);
    e.scale = ToEigenVector(layer.scale);
    e.translate = ToEigenVector(layer.translate);
    layers.push_back(std::move(e));
  }
  return EFlowModel(options_.dimension, std::move(layers), goal, speed(), "EFlowNet::ToEngine");
}

double EFlowNetImpl::speed() const { return std::exp(log_speed.item<double>()); }

}  // namespace foresight::imitation
