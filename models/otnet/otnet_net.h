#pragma once
/// OTNet's mixture density network in LibTorch (thesis ch 6, "Learning a Mixture of Stochastic
/// Processes"): an MLP (ReLU) from the map's similarity vector phi to the head of the engine
/// (inference/otnet/otnet_model.h: OtnetHead), trained with the exact mixture negative
/// log-likelihood of the trajectory weights w (thesis eq. lossF; log-sum-exp over components).
///
/// The net works on standardised inputs and targets: phi_hat = (phi - m_phi) / s_phi and
/// w_hat = (w - m_w) / s_w (OtnetNormalisation, from the training split). ToEngine folds both into
/// the first and last layers, so the engine reads raw phi and predicts raw w:
///   first layer  W' = W diag(1/s_phi),   b' = b - W (m_phi / s_phi),
///   mean rows    mu = s_w * mu_hat + m_w, log-scale rows   log s = log s_hat + log s_w.

#include <torch/torch.h>

#include <Eigen/Core>
#include <vector>

#include "inference/otnet/otnet_model.h"

namespace foresight::otnet {

struct OtnetNetOptions {
  int inputs = 0;                     ///< database size (>= 1)
  std::vector<int> hidden{256, 256};  ///< hidden widths (>= 1 layer, each >= 1)
  int components = 4;                 ///< Q >= 1
  int weights = 30;                   ///< 2M >= 2
  double dropout = 0.0;               ///< dropout after each hidden ReLU, in [0, 1)
  MixtureFamily family = MixtureFamily::kNormal;
};

/// The network's outputs split by OtnetHead (float32).
struct MixtureOutputs {
  torch::Tensor logits;     ///< [B, Q]
  torch::Tensor mean;       ///< [B, Q, 2M]
  torch::Tensor log_scale;  ///< [B, Q, 2M], clamped to [kLogScaleMin, kLogScaleMax]
};

class OtnetNetImpl : public torch::nn::Module {
 public:
  /// Error naming the bad option.
  explicit OtnetNetImpl(const OtnetNetOptions& options);
  /// Raw head [B, OtnetHead::Total()] for standardised phi [B, inputs].
  torch::Tensor forward(const torch::Tensor& phi);
  MixtureOutputs Split(const torch::Tensor& raw) const;
  const OtnetNetOptions& options() const { return options_; }
  /// The linear layers in order (hidden..., head).
  std::vector<torch::nn::Linear> linears() const { return linears_; }

 private:
  OtnetNetOptions options_;
  std::vector<torch::nn::Linear> linears_;
  torch::nn::Dropout dropout_{nullptr};
};
TORCH_MODULE(OtnetNet);

/// -log sum_q alpha_q prod_j p(w_j; mu_qj, s_qj) per row: [B] for w [B, 2M] (Normal or Laplace),
/// computed exactly with log-softmax and log-sum-exp.
torch::Tensor MixtureNegLogLikelihood(const MixtureOutputs& out, const torch::Tensor& w,
                                      MixtureFamily family);

struct OtnetNormalisation {
  Eigen::VectorXd input_mean, input_std;    ///< [D]; std floored at 1e-6
  Eigen::VectorXd weight_mean, weight_std;  ///< [2M]; std floored at 1e-6
  /// From the training maps' phi [maps x D] and the training weights [N x 2M].
  static OtnetNormalisation Fit(const Eigen::MatrixXd& phi, const Eigen::MatrixXd& w);
};

/// The engine MLP with the normalisation folded in (float); its Forward on raw phi equals the net's
/// on standardised phi followed by the de-standardisation (tested).
Mlp ExportMlp(OtnetNet& net, const OtnetNormalisation& norm);

}  // namespace foresight::otnet
