#pragma once
/// LibTorch model of the SPAN predictor: MLP F(past) -> mixture of matrix normals over W.
/// Module names ("mlp.<i>", "head") are the tensor names of the exported artifact.

#include <torch/torch.h>

#include "core/matrix_normal_head.h"
#include "models/span/span_config.h"

namespace foresight::span {

/// Decoded head outputs for a batch of B windows and R components.
struct MatrixNormalParams {
  torch::Tensor log_alpha;  ///< [B, R]
  torch::Tensor mean;       ///< [B, R, m, 2]
  torch::Tensor chol_u;     ///< [B, R, m, m] lower triangular (cholesky) or [B, R, m] diagonal
  torch::Tensor chol_v;     ///< [B, R, 3]: a, b, c of L_V = [[a, 0], [b, c]]
};

class NetImpl : public torch::nn::Module {
 public:
  NetImpl(int input_dim, const NetConfig& config, const HeadLayout& layout);
  /// @param x [B, input_dim] normalised inputs. @return raw head outputs [B, layout.Total()].
  torch::Tensor forward(const torch::Tensor& x);
  const HeadLayout& layout() const { return layout_; }
  /// Names of the dense layers in evaluation order ("mlp.0", ..., "head").
  std::vector<std::string> DenseLayerNames() const;

 private:
  HeadLayout layout_;
  torch::nn::Sequential mlp_{nullptr};
  torch::nn::Linear head_{nullptr};
  int num_hidden_ = 0;
};
TORCH_MODULE(Net);

/// Applies the activations of core/matrix_normal_head.h.
MatrixNormalParams DecodeHead(const torch::Tensor& raw, const HeadLayout& layout);

/// Exact negative log-likelihood of W under the mixture, per sample [B]
/// (spec/errata.md ch 5/7: -log sum_r alpha_r MN(W; M_r, U_r, V_r)).
/// @param w [B, m, 2] target weights.
torch::Tensor MixtureNll(const MatrixNormalParams& params, const torch::Tensor& w,
                         const HeadLayout& layout);

}  // namespace foresight::span
