#include "models/directional/directional_net.h"

#include <cmath>

#include "core/error.h"

namespace foresight {

DirectionalNetImpl::DirectionalNetImpl(DirectionalVariant variant, int spatial_size, int components, int hidden)
    : variant_(variant), components_(components), hidden_(hidden) {
  FS_THROW_UNLESS(spatial_size >= 1 && components >= 1 && (variant == DirectionalVariant::kSpatial || hidden >= 1),
                  "DirectionalNet: spatial_size ", spatial_size, ", components ", components, ", hidden ", hidden);
  int width = spatial_size;
  if (variant == DirectionalVariant::kSpatiotemporal) {
    lstm_ = register_module("lstm", torch::nn::LSTM(torch::nn::LSTMOptions(spatial_size, hidden).batch_first(true)));
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

torch::Tensor DirectionalNetImpl::forward(const torch::Tensor& phi_s, const torch::Tensor& phi_t) {
  if (variant_ == DirectionalVariant::kSpatial)
    return torch::cat({alpha_->forward(phi_s), mu_->forward(phi_s), kappa_->forward(phi_s)}, 1);
  // Sequence over the temporal inducing points: step k is phi_s * phi_t[k]  -> [B, M_t, M_s].
  const auto seq = phi_t.unsqueeze(2) * phi_s.unsqueeze(1);
  const auto out = std::get<0>(lstm_->forward(seq));
  const auto h = out.select(1, out.size(1) - 1);
  return torch::cat({alpha_->forward(h), mu_->forward(h), kappa_->forward(h)}, 1);
}

VonMisesMixtureTensors DecodeDirectionalHead(const torch::Tensor& raw, int R) {
  VonMisesMixtureTensors p;
  p.log_alpha = torch::log_softmax(raw.narrow(1, 0, R), 1);
  p.mu = raw.narrow(1, R, R);
  p.kappa = torch::exp(torch::clamp(raw.narrow(1, 2 * R, R), kDirectionalLogKappaMin, kDirectionalLogKappaMax));
  return p;
}

torch::Tensor LogBesselI0(const torch::Tensor& kappa) { return torch::log(torch::special::i0e(kappa)) + kappa; }

torch::Tensor VonMisesMixtureNll(const VonMisesMixtureTensors& p, const torch::Tensor& theta) {
  const auto log_vm = p.kappa * torch::cos(theta.unsqueeze(1) - p.mu) - std::log(2.0 * M_PI) - LogBesselI0(p.kappa);
  return -torch::logsumexp(p.log_alpha + log_vm, 1);
}

torch::Tensor HeadPenalty(DirectionalNetImpl& net, const DirectionalPenalty& c) {
  return c.lambda_alpha * net.alpha_head()->weight.square().sum() + c.lambda_mu * net.mu_head()->weight.square().sum() +
         c.lambda_kappa * net.kappa_head()->weight.square().sum();
}

torch::Tensor DirectionalLoss(DirectionalNetImpl& net, const torch::Tensor& phi_s, const torch::Tensor& phi_t,
                              const torch::Tensor& theta, const DirectionalPenalty& penalty) {
  const auto raw = net.forward(phi_s, phi_t);
  return VonMisesMixtureNll(DecodeDirectionalHead(raw, net.components()), theta).mean() + HeadPenalty(net, penalty);
}

}  // namespace foresight
