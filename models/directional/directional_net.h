#pragma once
/// LibTorch model of continuous spatiotemporal directional maps (thesis ch 4, table "architecture
/// of the spatiotemporal network"): kernel features -> LSTM (width 40R) -> three heads giving a
/// mixture of R von Mises; the spatial variant feeds the spatial features straight into the heads.
/// Module names ("lstm", "alpha", "mu", "kappa") are the tensor names of the exported artifact.

#include <torch/torch.h>

#include "inference/directional/directional_map.h"

namespace foresight {

class DirectionalNetImpl : public torch::nn::Module {
 public:
  /// @param spatial_size M_s; @param components R; @param hidden LSTM width (spatiotemporal only).
  DirectionalNetImpl(DirectionalVariant variant, int spatial_size, int components, int hidden);
  /// @param phi_s [B, M_s] spatial features; @param phi_t [B, M_t] temporal features (ignored by
  /// the spatial variant). @return raw head outputs [B, 3R]: alpha logits, means, log kappa.
  torch::Tensor forward(const torch::Tensor& phi_s, const torch::Tensor& phi_t);

  DirectionalVariant variant() const { return variant_; }
  int components() const { return components_; }
  int hidden() const { return hidden_; }
  torch::nn::Linear alpha_head() const { return alpha_; }
  torch::nn::Linear mu_head() const { return mu_; }
  torch::nn::Linear kappa_head() const { return kappa_; }

 private:
  DirectionalVariant variant_;
  int components_ = 5, hidden_ = 0;
  torch::nn::LSTM lstm_{nullptr};
  torch::nn::Linear alpha_{nullptr}, mu_{nullptr}, kappa_{nullptr};
};
TORCH_MODULE(DirectionalNet);

/// Decoded mixture for B queries: log alpha, mu (unwrapped), kappa, each [B, R].
struct VonMisesMixtureTensors {
  torch::Tensor log_alpha, mu, kappa;
};
/// softmax / identity / exp(clamp(., kDirectionalLogKappaMin, kDirectionalLogKappaMax)).
VonMisesMixtureTensors DecodeDirectionalHead(const torch::Tensor& raw, int components);

/// log I0(kappa), finite for any kappa >= 0: log(i0e(kappa)) + kappa (spec/errata.md ch 4).
torch::Tensor LogBesselI0(const torch::Tensor& kappa);

/// -log sum_r alpha_r VM(theta; mu_r, kappa_r) per sample [B]; theta [B] (rad). Thesis eq. (ANLL).
torch::Tensor VonMisesMixtureNll(const VonMisesMixtureTensors& p, const torch::Tensor& theta);

/// L2 penalties on the head weights (biases excluded).
struct DirectionalPenalty {
  double lambda_alpha = 0.001, lambda_mu = 0.0, lambda_kappa = 0.001;
};
/// lambda_a ||W_a||^2 + lambda_m ||W_m||^2 + lambda_k ||W_k||^2 (added to the loss, spec/errata.md).
torch::Tensor HeadPenalty(DirectionalNetImpl& net, const DirectionalPenalty& penalty);
/// Thesis L_reg = mean NLL + HeadPenalty (the penalty added; spec/errata.md ch 4).
torch::Tensor DirectionalLoss(DirectionalNetImpl& net, const torch::Tensor& phi_s, const torch::Tensor& phi_t,
                              const torch::Tensor& theta, const DirectionalPenalty& penalty);

}  // namespace foresight
