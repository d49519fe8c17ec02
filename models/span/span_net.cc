#include "models/span/span_net.h"

#include <cmath>

namespace foresight::span {

NetImpl::NetImpl(int input_dim, const NetConfig& config, const HeadLayout& layout)
    : layout_(layout) {
  mlp_ = torch::nn::Sequential();
  int width = input_dim;
  for (int h : config.hidden) {
    mlp_->push_back(torch::nn::Linear(width, h));
    mlp_->push_back(torch::nn::ReLU());
    width = h;
  }
  num_hidden_ = static_cast<int>(config.hidden.size());
  register_module("mlp", mlp_);
  head_ = register_module("head", torch::nn::Linear(width, layout.Total()));
  // Start near a broad, well-conditioned distribution: small head weights.
  torch::NoGradGuard no_grad;
  head_->weight.mul_(0.1);
  head_->bias.zero_();
}

torch::Tensor NetImpl::forward(const torch::Tensor& x) { return head_->forward(mlp_->forward(x)); }

std::vector<std::string> NetImpl::DenseLayerNames() const {
  std::vector<std::string> names;
  for (int i = 0; i < num_hidden_; ++i) names.push_back("mlp." + std::to_string(2 * i));
  names.push_back("head");
  return names;
}

MatrixNormalParams DecodeHead(const torch::Tensor& raw, const HeadLayout& L) {
  const int64_t B = raw.size(0), R = L.components, m = L.basis;
  const auto z = raw.view({B, R, L.PerComponent()});
  MatrixNormalParams p;
  p.log_alpha = torch::log_softmax(z.select(2, 0), 1);
  p.mean = z.narrow(2, 1, 2 * m).reshape({B, R, m, 2});
  const auto u = z.narrow(2, 1 + 2 * m, L.UBlock());
  if (L.u_param == UParam::kDiagonal) {
    p.chol_u = torch::exp(torch::clamp(u, HeadLayout::kLogDiagMin, HeadLayout::kLogDiagMax));
  } else {
    const auto idx = torch::tril_indices(m, m, 0, torch::kLong);
    const auto is_diag = idx[0].eq(idx[1]);
    const auto vals = torch::where(
        is_diag, torch::exp(torch::clamp(u, HeadLayout::kLogDiagMin, HeadLayout::kLogDiagMax)), u);
    auto chol = torch::zeros({B, R, m, m}, raw.options());
    chol.index_put_({torch::indexing::Slice(), torch::indexing::Slice(), idx[0], idx[1]}, vals);
    p.chol_u = chol;
  }
  const auto v = z.narrow(2, 1 + 2 * m + L.UBlock(), 3);
  const auto a =
      torch::exp(torch::clamp(v.select(2, 0), HeadLayout::kLogDiagMin, HeadLayout::kLogDiagMax));
  const auto c =
      torch::exp(torch::clamp(v.select(2, 2), HeadLayout::kLogDiagMin, HeadLayout::kLogDiagMax));
  p.chol_v = torch::stack({a, v.select(2, 1), c}, 2);
  return p;
}

torch::Tensor MixtureNll(const MatrixNormalParams& p, const torch::Tensor& w, const HeadLayout& L) {
  const int64_t m = L.basis;
  const auto d = w.unsqueeze(1) - p.mean;  // [B, R, m, 2]
  torch::Tensor a, log_det_u;
  if (L.u_param == UParam::kDiagonal) {
    a = d / p.chol_u.unsqueeze(-1);
    log_det_u = 2.0 * torch::log(p.chol_u).sum(-1);
  } else {
    a = torch::linalg_solve_triangular(p.chol_u, d, /*upper=*/false, /*left=*/true,
                                       /*unitriangular=*/false);
    log_det_u = 2.0 * torch::log(torch::diagonal(p.chol_u, 0, -2, -1)).sum(-1);
  }
  // B = A L_V^-T, closed form for the 2 x 2 lower factor [[la, 0], [lb, lc]].
  const auto la = p.chol_v.select(2, 0).unsqueeze(-1);
  const auto lb = p.chol_v.select(2, 1).unsqueeze(-1);
  const auto lc = p.chol_v.select(2, 2).unsqueeze(-1);
  const auto b0 = a.select(-1, 0) / la;
  const auto b1 = (a.select(-1, 1) - lb * b0) / lc;
  const auto quad = (b0.square() + b1.square()).sum(-1);  // [B, R]
  const auto log_det_v = 2.0 * (torch::log(la.squeeze(-1)) + torch::log(lc.squeeze(-1)));
  const auto log_comp = -0.5 * quad - static_cast<double>(m) * std::log(2.0 * M_PI) -
                        0.5 * static_cast<double>(m) * log_det_v - log_det_u;
  return -torch::logsumexp(p.log_alpha + log_comp, 1);
}

}  // namespace foresight::span
