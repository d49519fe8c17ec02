#include "models/constrained/naive_net.h"

#include "core/error.h"

namespace foresight::constrained {

NaiveNetImpl::NaiveNetImpl(int input_dim, const std::vector<int>& hidden, int output_dim) {
  FS_THROW_UNLESS(input_dim >= 1 && output_dim >= 1, "NaiveNet: input_dim ", input_dim,
                  " and output_dim ", output_dim, " must be positive");
  mlp_ = torch::nn::Sequential();
  int width = input_dim;
  for (int h : hidden) {
    FS_THROW_UNLESS(h >= 1, "NaiveNet: hidden width ", h, " must be positive");
    mlp_->push_back(torch::nn::Linear(width, h));
    mlp_->push_back(torch::nn::ReLU());
    width = h;
  }
  num_hidden_ = static_cast<int>(hidden.size());
  register_module("mlp", mlp_);
  head_ = register_module("head", torch::nn::Linear(width, output_dim));
}

torch::Tensor NaiveNetImpl::forward(const torch::Tensor& x) {
  return head_->forward(num_hidden_ > 0 ? mlp_->forward(x) : x);
}

std::vector<std::string> NaiveNetImpl::DenseLayerNames() const {
  std::vector<std::string> names;
  for (int i = 0; i < num_hidden_; ++i) names.push_back("mlp." + std::to_string(2 * i));
  names.push_back("head");
  return names;
}

}  // namespace foresight::constrained
