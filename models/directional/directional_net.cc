#include "models/directional/directional_net.h"

#include <cmath>

#include "core/error.h"

namespace foresight::directional {

NetImpl::NetImpl(Variant variant, int spatial_size, int components, int hidden, double max_kappa)
    : variant_(variant), components_(components), hidden_(hidden), max_kappa_(max_kappa) {
  FS_THROW_UNLESS(std::isfinite(max_kappa) && max_kappa > std::exp(kDirectionalLogKappaMin),
                  "DirectionalNet: max_kappa ", max_kappa);
  FS_THROW_UNLESS(
      spatial_size >= 1 && components >= 1 && (variant == Variant::kSpatial || hidden >= 1),
      "DirectionalNet: spatial_size ", spatial_size, ", components ", components, ", hidden ",
      hidden);
  int width = spatial_size;
  if (variant == Variant::kSpatiotemporal) {
    // PyTorch's LSTM parameters and initialisation: U(-1/sqrt(H), 1/sqrt(H)).
    lstm_ = register_module("lstm", std::make_shared<torch::nn::Module>("LSTM"));
    const double k = 1.0 / std::sqrt(static_cast<double>(hidden));
    auto u = [k](std::vector<int64_t> shape) { return torch::empty(shape).uniform_(-k, k); };
    weight_ih_ = lstm_->register_parameter("weight_ih_l0", u({4 * hidden, spatial_size}));
    weight_hh_ = lstm_->register_parameter("weight_hh_l0", u({4 * hidden, hidden}));
    bias_ih_ = lstm_->register_parameter("bias_ih_l0", u({4 * hidden}));
    bias_hh_ = lstm_->register_parameter("bias_hh_l0", u({4 * hidden}));
    width = hidden;
  } else {
    hidden_ = 0;
  }
  alpha_ = register_module("alpha", torch::nn::Linear(width, components));
  mu_ = register_module("mu", torch::nn::Linear(width, components));
  kappa_ = register_module("kappa", torch::nn::Linear(width, components));
  // Start from distinct means spread over the circle, equal weights and kappa = 1.
  torch::NoGradGuard no_grad;
  for (int r = 0; r < components; ++r) mu_->bias[r] = -M_PI + 2.0 * M_PI * (r + 0.5) / components;
  alpha_->bias.zero_();
  kappa_->bias.zero_();
}

torch::Tensor NetImpl::Heads(const torch::Tensor& z) {
  return torch::cat({alpha_->forward(z), mu_->forward(z), kappa_->forward(z)}, 1);
}

torch::Tensor NetImpl::Recur(const torch::Tensor& proj, const torch::Tensor& phi_t) {
  const auto bias = bias_ih_ + bias_hh_;
  torch::Tensor h, c;
  for (int64_t k = 0; k < phi_t.size(1); ++k) {
    auto gates = proj * phi_t.narrow(1, k, 1) + bias;
    if (k > 0) gates = gates + torch::matmul(h, weight_hh_.t());  // h = 0 before the first step
    const auto g = gates.chunk(4, 1);
    const auto i = torch::sigmoid(g[0]), f = torch::sigmoid(g[1]), cand = torch::tanh(g[2]),
               o = torch::sigmoid(g[3]);
    c = k > 0 ? f * c + i * cand : i * cand;
    h = o * torch::tanh(c);
  }
  return h;
}

torch::Tensor NetImpl::forward(const torch::Tensor& phi_s, const torch::Tensor& phi_t) {
  if (variant_ == Variant::kSpatial) return Heads(phi_s);
  return Heads(Recur(torch::matmul(phi_s, weight_ih_.t()), phi_t));
}

torch::Tensor NetImpl::forward_sparse(const torch::Tensor& index, const torch::Tensor& value,
                                      const torch::Tensor& offsets, const torch::Tensor& phi_t) {
  namespace F = torch::nn::functional;
  auto bag = [&](const torch::Tensor& weight_t) {  // sum_j value_j weight_t[index_j] per sample
    return F::embedding_bag(index, weight_t,
                            F::EmbeddingBagFuncOptions()
                                .offsets(offsets)
                                .mode(torch::kSum)
                                .per_sample_weights(value)
                                .include_last_offset(true));
  };
  if (variant_ == Variant::kSpatial) {
    const auto w = torch::cat({alpha_->weight, mu_->weight, kappa_->weight}, 0).t().contiguous();
    return bag(w) + torch::cat({alpha_->bias, mu_->bias, kappa_->bias}, 0);
  }
  return Heads(Recur(bag(weight_ih_.t().contiguous()), phi_t));
}

VonMisesMixtureTensors DecodeVonMisesHead(const torch::Tensor& raw, int R, double max_kappa) {
  VonMisesMixtureTensors p;
  p.log_alpha = torch::log_softmax(raw.narrow(1, 0, R), 1);
  p.mu = raw.narrow(1, R, R);
  p.kappa = torch::exp(
      torch::clamp(raw.narrow(1, 2 * R, R), kDirectionalLogKappaMin, std::log(max_kappa)));
  return p;
}

torch::Tensor LogBesselI0(const torch::Tensor& kappa) {
  return torch::log(torch::special::i0e(kappa)) + kappa;
}

torch::Tensor VonMisesMixtureNll(const VonMisesMixtureTensors& p, const torch::Tensor& theta) {
  const auto log_vm =
      p.kappa * torch::cos(theta.unsqueeze(1) - p.mu) - std::log(2.0 * M_PI) - LogBesselI0(p.kappa);
  return -torch::logsumexp(p.log_alpha + log_vm, 1);
}

torch::Tensor HeadPenalty(NetImpl& net, const Penalty& c) {
  return c.lambda_alpha * net.alpha_head()->weight.square().sum() +
         c.lambda_mu * net.mu_head()->weight.square().sum() +
         c.lambda_kappa * net.kappa_head()->weight.square().sum();
}

torch::Tensor LossFromRaw(NetImpl& net, const torch::Tensor& raw, const torch::Tensor& theta,
                          const Penalty& penalty) {
  return VonMisesMixtureNll(DecodeVonMisesHead(raw, net.components(), net.max_kappa()), theta)
             .mean() +
         HeadPenalty(net, penalty);
}

torch::Tensor Loss(NetImpl& net, const torch::Tensor& phi_s, const torch::Tensor& phi_t,
                   const torch::Tensor& theta, const Penalty& penalty) {
  return LossFromRaw(net, net.forward(phi_s, phi_t), theta, penalty);
}

}  // namespace foresight::directional
