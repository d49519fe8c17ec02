#pragma once
/// LibTorch model of continuous spatiotemporal directional maps (thesis ch 4, table "architecture
/// of the spatiotemporal network"): kernel features -> LSTM (width 40R) -> three heads giving a
/// mixture of R von Mises; the spatial variant feeds the spatial features straight into the heads.
/// Module names ("lstm", "alpha", "mu", "kappa") are the tensor names of the exported artifact.
///
/// The LSTM is PyTorch's single-layer LSTM written out (same parameters lstm.weight_ih_l0,
/// weight_hh_l0, bias_ih_l0, bias_hh_l0, gate order i, f, g, o, zero initial state) so that the
/// input projection can be taken once per sample: step k's input is phi_s * phi_t[k], hence
/// W_ih x_k = phi_t[k] (W_ih phi_s), and W_ih phi_s is an embedding bag over the few non-zero
/// spatial features (forward_sparse). The dense forward gives the same values (tests, parity).

#include <torch/torch.h>

#include "inference/directional/directional_map.h"

namespace foresight::directional {

class NetImpl : public torch::nn::Module {
 public:
  /// @param spatial_size M_s; @param components R; @param hidden LSTM width (spatiotemporal only).
  /// @param max_kappa cap of the concentrations (log-kappa head clamp).
  NetImpl(Variant variant, int spatial_size, int components, int hidden,
          double max_kappa = kDirectionalDefaultMaxKappa);
  /// @param phi_s [B, M_s] spatial features; @param phi_t [B, M_t] temporal features (ignored by
  /// the spatial variant). @return raw head outputs [B, 3R]: alpha logits, means, log kappa.
  torch::Tensor forward(const torch::Tensor& phi_s, const torch::Tensor& phi_t);
  /// The same from sparse spatial features (DirectionalFeatures::SpatialSparseBatch): `index` and
  /// `value` [nnz], `offsets` [B + 1] (int64, last = nnz).
  torch::Tensor forward_sparse(const torch::Tensor& index, const torch::Tensor& value,
                               const torch::Tensor& offsets, const torch::Tensor& phi_t);

  Variant variant() const { return variant_; }
  int components() const { return components_; }
  int hidden() const { return hidden_; }
  double max_kappa() const { return max_kappa_; }
  torch::nn::Linear alpha_head() const { return alpha_; }
  torch::nn::Linear mu_head() const { return mu_; }
  torch::nn::Linear kappa_head() const { return kappa_; }

 private:
  torch::Tensor Heads(const torch::Tensor& z);
  /// LSTM over the M_t steps from the input projection proj = W_ih phi_s [B, 4H]: last h [B, H].
  torch::Tensor Recur(const torch::Tensor& proj, const torch::Tensor& phi_t);

  Variant variant_;
  int components_ = 5, hidden_ = 0;
  double max_kappa_ = kDirectionalDefaultMaxKappa;
  std::shared_ptr<torch::nn::Module> lstm_;
  torch::Tensor weight_ih_, weight_hh_, bias_ih_, bias_hh_;
  torch::nn::Linear alpha_{nullptr}, mu_{nullptr}, kappa_{nullptr};
};
TORCH_MODULE(Net);

/// Decoded mixture for B queries: log alpha, mu (unwrapped), kappa, each [B, R].
struct VonMisesMixtureTensors {
  torch::Tensor log_alpha, mu, kappa;
};
/// softmax / identity / exp(clamp(., kDirectionalLogKappaMin, log max_kappa)).
VonMisesMixtureTensors DecodeVonMisesHead(const torch::Tensor& raw, int components,
                                          double max_kappa = kDirectionalDefaultMaxKappa);

/// log I0(kappa), finite for any kappa >= 0: log(i0e(kappa)) + kappa (spec/errata.md ch 4).
torch::Tensor LogBesselI0(const torch::Tensor& kappa);

/// -log sum_r alpha_r VM(theta; mu_r, kappa_r) per sample [B]; theta [B] (rad). Thesis eq. (ANLL).
torch::Tensor VonMisesMixtureNll(const VonMisesMixtureTensors& p, const torch::Tensor& theta);

/// L2 penalties on the head weights (biases excluded).
struct Penalty {
  double lambda_alpha = 0.001, lambda_mu = 0.0, lambda_kappa = 0.001;
};
/// lambda_a ||W_a||^2 + lambda_m ||W_m||^2 + lambda_k ||W_k||^2 (added to the loss,
/// spec/errata.md).
torch::Tensor HeadPenalty(NetImpl& net, const Penalty& penalty);
/// Thesis L_reg = mean NLL + HeadPenalty (the penalty added; spec/errata.md ch 4).
torch::Tensor Loss(NetImpl& net, const torch::Tensor& phi_s, const torch::Tensor& phi_t,
                   const torch::Tensor& theta, const Penalty& penalty);
/// The same from raw head outputs [B, 3R] of `net`.
torch::Tensor LossFromRaw(NetImpl& net, const torch::Tensor& raw, const torch::Tensor& theta,
                          const Penalty& penalty);

}  // namespace foresight::directional
