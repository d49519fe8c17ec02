#include "training/otnet/task.h"

#include <algorithm>

#include "core/error.h"

namespace foresight::otnet {
namespace {

bool AllFinite(const torch::Tensor& t) {
  return t.numel() == 0 || torch::isfinite(t).all().item<bool>();
}

/// Validation rows per forward pass in ValidationLoss (bounds the activations' memory).
constexpr std::int64_t kValidationChunk = 8192;

}  // namespace

OtnetTask::OtnetTask(OtnetNet net, torch::Tensor phi_train, torch::Tensor map_train,
                     torch::Tensor w_train, torch::Tensor phi_val, torch::Tensor map_val,
                     torch::Tensor w_val)
    : net_(std::move(net)) {
  FS_THROW_UNLESS(!net_.is_empty(), "OtnetTask: no network");
  const OtnetNetOptions& o = net_->options();
  const auto check = [&o](const char* split, const torch::Tensor& phi, const torch::Tensor& map,
                          const torch::Tensor& w, torch::Tensor* phi_out, torch::Tensor* map_out,
                          torch::Tensor* w_out) {
    FS_THROW_UNLESS(phi.defined() && phi.dim() == 2 && phi.size(0) >= 1 && phi.size(1) == o.inputs,
                    "OtnetTask: phi_", split, " must be [maps, ", o.inputs,
                    "] with maps >= 1, got ", phi.defined() ? phi.sizes() : torch::IntArrayRef{});
    FS_THROW_UNLESS(w.defined() && w.dim() == 2 && w.size(0) >= 1 && w.size(1) == o.weights,
                    "OtnetTask: w_", split, " must be [N, ", o.weights, "] with N >= 1, got ",
                    w.defined() ? w.sizes() : torch::IntArrayRef{});
    FS_THROW_UNLESS(map.defined() && map.dim() == 1 && map.size(0) == w.size(0), "OtnetTask: map_",
                    split, " must be [", w.size(0), "] (one map per row of w_", split, "), got ",
                    map.defined() ? map.sizes() : torch::IntArrayRef{});
    FS_THROW_UNLESS(!map.is_floating_point() && !map.is_complex(), "OtnetTask: map_", split,
                    " must hold integer map indices, got ", map.scalar_type());
    *phi_out = phi.detach().to(torch::kFloat32).contiguous();
    *w_out = w.detach().to(torch::kFloat32).contiguous();
    *map_out = map.detach().to(torch::kInt64).contiguous();
    FS_THROW_UNLESS(AllFinite(*phi_out), "OtnetTask: phi_", split, " contains a non-finite value");
    FS_THROW_UNLESS(AllFinite(*w_out), "OtnetTask: w_", split, " contains a non-finite value");
    const std::int64_t lo = map_out->min().item<std::int64_t>();
    const std::int64_t hi = map_out->max().item<std::int64_t>();
    FS_THROW_UNLESS(lo >= 0 && hi < phi.size(0), "OtnetTask: map_", split, " indices span [", lo,
                    ", ", hi, "] but phi_", split, " has ", phi.size(0), " rows");
  };
  check("train", phi_train, map_train, w_train, &phi_train_, &map_train_, &w_train_);
  check("val", phi_val, map_val, w_val, &phi_val_, &map_val_, &w_val_);
}

torch::Tensor OtnetTask::BatchLoss(const torch::Tensor& indices) {
  const torch::Tensor i = indices.to(torch::kInt64);
  const torch::Tensor phi = phi_train_.index_select(0, map_train_.index_select(0, i));
  const torch::Tensor nll = MixtureNegLogLikelihood(
      net_->Split(net_->forward(phi)), w_train_.index_select(0, i), net_->options().family);
  return nll.mean() / static_cast<double>(net_->options().weights);
}

double OtnetTask::ValidationLoss() {
  torch::NoGradGuard no_grad;
  // eval() (no dropout) for the evaluation, then the previous mode again, even on an Error.
  struct ModeGuard {
    torch::nn::Module& module;
    bool was_training;
    ~ModeGuard() { module.train(was_training); }
  } guard{*net_, net_->is_training()};
  net_->eval();
  const std::int64_t n = w_val_.size(0);
  double total = 0;
  for (std::int64_t start = 0; start < n; start += kValidationChunk) {
    const std::int64_t len = std::min(kValidationChunk, n - start);
    const torch::Tensor phi = phi_val_.index_select(0, map_val_.narrow(0, start, len));
    total += MixtureNegLogLikelihood(net_->Split(net_->forward(phi)), w_val_.narrow(0, start, len),
                                     net_->options().family)
                 .to(torch::kFloat64)
                 .sum()
                 .item<double>();
  }
  return total / static_cast<double>(n) / static_cast<double>(net_->options().weights);
}

}  // namespace foresight::otnet
