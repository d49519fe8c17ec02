#pragma once
/// The naive network baseline of structurally constrained prediction (thesis ch 7, "NN-naive"):
/// a ReLU MLP from the normalised ego-frame past [2p] to the ego-frame future [2f], trained by
/// mean squared error (thesis: 560 -> 180 -> 180 -> N_t). Module names ("mlp.<i>", "head") are
/// the tensor names of the exported artifact (inference/prediction/naive_predictor.h).

#include <torch/torch.h>

#include <string>
#include <vector>

namespace foresight::constrained {

class NaiveNetImpl : public torch::nn::Module {
 public:
  /// @param input_dim 2p. @param hidden widths of the ReLU layers. @param output_dim 2f.
  NaiveNetImpl(int input_dim, const std::vector<int>& hidden, int output_dim);
  /// @param x [B, 2p] normalised inputs. @return [B, 2f] ego-frame future (m).
  torch::Tensor forward(const torch::Tensor& x);
  /// Names of the dense layers in evaluation order ("mlp.0", "mlp.2", ..., "head").
  std::vector<std::string> DenseLayerNames() const;

 private:
  torch::nn::Sequential mlp_{nullptr};
  torch::nn::Linear head_{nullptr};
  int num_hidden_ = 0;
};
TORCH_MODULE(NaiveNet);

}  // namespace foresight::constrained
