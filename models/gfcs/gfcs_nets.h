#pragma once
/// LibTorch models of self-supervised GFCS (thesis ch 9): the energy model E_theta(x_c, y), its
/// InfoNCE loss, and the autoencoder of the basis-point distances. Both export to the dense
/// ReLU engine (inference/engine/dense.h) that inference/manipulation/energy_model.h evaluates.

#include <torch/torch.h>

#include "inference/engine/dense.h"

namespace foresight::gfcs {

/// Dense layers with ReLU between them and none after the last (the engine's Mlp semantics).
class DenseReluNetImpl : public torch::nn::Module {
 public:
  /// @param sizes input, hidden..., output widths (at least two).
  explicit DenseReluNetImpl(const std::vector<int>& sizes);
  torch::Tensor forward(torch::Tensor x);
  /// The same network as engine weights (float).
  Mlp ToMlp() const;
  /// Copies `mlp`'s weights in (shapes must match).
  void LoadMlp(const Mlp& mlp);

 private:
  std::vector<torch::nn::Linear> layers_;
};
TORCH_MODULE(DenseReluNet);

/// E_theta(x_c, y) = MLP([x_c, u]) with u the commands normalised to [-1, 1] (the engine's layout).
class EnergyNetImpl : public torch::nn::Module {
 public:
  EnergyNetImpl(int context_size, int command_size, int hidden, int layers);
  /// @param context [B, C]; @param u [B, K, D] K candidates per context. @return E [B, K].
  torch::Tensor forward(const torch::Tensor& context, const torch::Tensor& u);
  DenseReluNet& net() { return net_; }
  const DenseReluNet& net() const { return net_; }

 private:
  DenseReluNet net_{nullptr};
};
TORCH_MODULE(EnergyNet);

/// InfoNCE (thesis eq. "lossimpli", errata: low energy is good), mean over the B positives:
/// -log( e^{-E_pos} / (e^{-E_pos} + sum_k e^{-E_neg,k}) ).
/// @param energy_pos [B]; @param energy_neg [B, N]; @param valid undefined (every negative
/// counts) or bool [B, N]: the negatives that count (the others leave the sum, as if absent).
torch::Tensor InfoNceLoss(const torch::Tensor& energy_pos, const torch::Tensor& energy_neg,
                          const torch::Tensor& valid = {});

/// Encoder N_R -> hidden -> encoding, decoder back; trained on reconstruction error.
class BpsAutoencoderImpl : public torch::nn::Module {
 public:
  BpsAutoencoderImpl(int inputs, int hidden, int encoding);
  torch::Tensor forward(const torch::Tensor& x);  ///< reconstruction [B, N_R]
  DenseReluNet& encoder() { return encoder_; }

 private:
  DenseReluNet encoder_{nullptr}, decoder_{nullptr};
};
TORCH_MODULE(BpsAutoencoder);

}  // namespace foresight::gfcs
