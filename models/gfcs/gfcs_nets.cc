#include "models/gfcs/gfcs_nets.h"

#include <limits>

#include "core/error.h"

namespace foresight::gfcs {

DenseReluNetImpl::DenseReluNetImpl(const std::vector<int>& sizes) {
  FS_THROW_UNLESS(sizes.size() >= 2, "DenseReluNet: needs an input and an output size, got ",
                  sizes.size(), " sizes");
  for (std::size_t i = 0; i + 1 < sizes.size(); ++i)
    layers_.push_back(
        register_module("l" + std::to_string(i), torch::nn::Linear(sizes[i], sizes[i + 1])));
}

torch::Tensor DenseReluNetImpl::forward(torch::Tensor x) {
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    x = layers_[i]->forward(x);
    if (i + 1 < layers_.size()) x = torch::relu(x);
  }
  return x;
}

Mlp DenseReluNetImpl::ToMlp() const {
  std::vector<DenseLayer> out;
  for (const torch::nn::Linear& l : layers_) {
    const torch::Tensor w = l->weight.detach().contiguous().to(torch::kFloat32);
    const torch::Tensor b = l->bias.detach().contiguous().to(torch::kFloat32);
    DenseLayer d;
    d.weight =
        Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            w.data_ptr<float>(), w.size(0), w.size(1));
    d.bias = Eigen::Map<const Eigen::VectorXf>(b.data_ptr<float>(), b.size(0));
    out.push_back(std::move(d));
  }
  return Mlp(std::move(out));
}

void DenseReluNetImpl::LoadMlp(const Mlp& mlp) {
  FS_THROW_UNLESS(mlp.layers().size() == layers_.size(), "DenseReluNet: ", mlp.layers().size(),
                  " layers given, the network has ", layers_.size());
  torch::NoGradGuard no_grad;
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    const DenseLayer& d = mlp.layers()[i];
    torch::Tensor& w = layers_[i]->weight;
    FS_THROW_UNLESS(d.weight.rows() == w.size(0) && d.weight.cols() == w.size(1),
                    "DenseReluNet: layer ", i, " is ", d.weight.rows(), " x ", d.weight.cols(),
                    ", the network's ", w.size(0), " x ", w.size(1));
    const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = d.weight;
    w.copy_(
        torch::from_blob(const_cast<float*>(rm.data()), {w.size(0), w.size(1)}, torch::kFloat32));
    layers_[i]->bias.copy_(
        torch::from_blob(const_cast<float*>(d.bias.data()), {d.bias.size()}, torch::kFloat32));
  }
}

EnergyNetImpl::EnergyNetImpl(int context_size, int command_size, int hidden, int layers) {
  std::vector<int> sizes{context_size + command_size};
  for (int i = 0; i < layers; ++i) sizes.push_back(hidden);
  sizes.push_back(1);
  net_ = register_module("net", DenseReluNet(sizes));
}

torch::Tensor EnergyNetImpl::forward(const torch::Tensor& context, const torch::Tensor& u) {
  const std::int64_t b = u.size(0), k = u.size(1);
  const torch::Tensor x =
      torch::cat({context.unsqueeze(1).expand({b, k, context.size(1)}), u}, /*dim=*/2);
  return net_->forward(x.reshape({b * k, x.size(2)})).reshape({b, k});
}

torch::Tensor InfoNceLoss(const torch::Tensor& energy_pos, const torch::Tensor& energy_neg,
                          const torch::Tensor& valid) {
  torch::Tensor logits = -torch::cat({energy_pos.unsqueeze(1), energy_neg}, 1);  // [B, 1 + N]
  if (valid.defined()) {
    FS_THROW_UNLESS(valid.sizes() == energy_neg.sizes() && valid.scalar_type() == torch::kBool,
                    "InfoNCE: the mask must be bool and shaped as the negatives' energies");
    // An absent negative's logit is -inf: exp(-inf) = 0 in the sum and in its gradient (the
    // positive's logit is finite, so logsumexp's maximum is).
    const torch::Tensor keep = torch::cat({torch::ones_like(valid.narrow(1, 0, 1)), valid}, 1);
    logits = logits.masked_fill(keep.logical_not(), -std::numeric_limits<float>::infinity());
  }
  // -log softmax(-E)_0 = E_pos + logsumexp(-E)
  return (energy_pos + torch::logsumexp(logits, 1)).mean();
}

BpsAutoencoderImpl::BpsAutoencoderImpl(int inputs, int hidden, int encoding) {
  encoder_ = register_module("encoder", DenseReluNet(std::vector<int>{inputs, hidden, encoding}));
  decoder_ = register_module("decoder", DenseReluNet(std::vector<int>{encoding, hidden, inputs}));
}

torch::Tensor BpsAutoencoderImpl::forward(const torch::Tensor& x) {
  return decoder_->forward(encoder_->forward(x));
}

}  // namespace foresight::gfcs
