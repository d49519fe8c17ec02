#include "models/span/span_net.h"

#include <gtest/gtest.h>

#include "core/matrix_normal.h"

namespace foresight::span {
namespace {

/// Builds the core (Eigen, double) mixture of sample b from decoded torch parameters.
MatrixNormalMixture ToCore(const MatrixNormalParams& p, const HeadLayout& L, int b) {
  MatrixNormalMixture mix;
  const int m = L.basis;
  for (int r = 0; r < L.components; ++r) {
    mix.weights.push_back(std::exp(p.log_alpha[b][r].item<double>()));
    MatrixNormal d;
    d.mean.resize(m, 2);
    d.chol_u = Eigen::MatrixXd::Zero(m, m);
    for (int i = 0; i < m; ++i) {
      d.mean(i, 0) = p.mean[b][r][i][0].item<double>();
      d.mean(i, 1) = p.mean[b][r][i][1].item<double>();
      if (L.u_param == UParam::kDiagonal) {
        d.chol_u(i, i) = p.chol_u[b][r][i].item<double>();
      } else {
        for (int j = 0; j <= i; ++j) d.chol_u(i, j) = p.chol_u[b][r][i][j].item<double>();
      }
    }
    d.chol_v << p.chol_v[b][r][0].item<double>(), 0, p.chol_v[b][r][1].item<double>(),
        p.chol_v[b][r][2].item<double>();
    mix.components.push_back(d);
  }
  return mix;
}

struct Case {
  int m, R;
  UParam u;
};

class MixtureNllTest : public ::testing::TestWithParam<Case> {};

TEST_P(MixtureNllTest, MatchesIndependentMatrixNormalDensity) {
  // The core density is itself checked against vec(W) ~ N(vec(M), V kron U) in matrix_normal_test.
  const Case c = GetParam();
  const HeadLayout L{c.m, c.R, c.u};
  torch::manual_seed(0);
  const auto raw = 0.5 * torch::randn({4, L.Total()}, torch::kFloat64);
  const auto w = torch::randn({4, c.m, 2}, torch::kFloat64);
  const auto params = DecodeHead(raw, L);
  const auto nll = MixtureNll(params, w, L);
  for (int b = 0; b < 4; ++b) {
    Eigen::MatrixXd wm(c.m, 2);
    for (int i = 0; i < c.m; ++i)
      wm(i, 0) = w[b][i][0].item<double>(), wm(i, 1) = w[b][i][1].item<double>();
    EXPECT_NEAR(nll[b].item<double>(), -ToCore(params, L, b).LogPdf(wm), 1e-9);
  }
}

TEST_P(MixtureNllTest, GradientMatchesFiniteDifferences) {
  const Case c = GetParam();
  const HeadLayout L{c.m, c.R, c.u};
  torch::manual_seed(1);
  auto raw = (0.3 * torch::randn({2, L.Total()}, torch::kFloat64)).requires_grad_(true);
  const auto w = torch::randn({2, c.m, 2}, torch::kFloat64);
  auto loss_of = [&](const torch::Tensor& z) { return MixtureNll(DecodeHead(z, L), w, L).sum(); };
  loss_of(raw).backward();
  const auto grad = raw.grad().clone();
  torch::NoGradGuard no_grad;
  const double h = 1e-6;
  double max_err = 0, max_grad = 0;
  for (int64_t k = 0; k < raw.numel(); ++k) {
    auto plus = raw.detach().clone(), minus = raw.detach().clone();
    plus.view(-1)[k] += h;
    minus.view(-1)[k] -= h;
    const double fd = (loss_of(plus).item<double>() - loss_of(minus).item<double>()) / (2 * h);
    max_err = std::max(max_err, std::abs(fd - grad.view(-1)[k].item<double>()));
    max_grad = std::max(max_grad, std::abs(fd));
  }
  EXPECT_LT(max_err, 1e-5 * (1 + max_grad));
}

INSTANTIATE_TEST_SUITE_P(Heads, MixtureNllTest,
                         ::testing::Values(Case{1, 1, UParam::kCholesky},
                                           Case{6, 1, UParam::kCholesky},
                                           Case{6, 1, UParam::kDiagonal},
                                           Case{5, 3, UParam::kDiagonal},
                                           Case{4, 2, UParam::kCholesky}));

TEST(SpanNet, LayerNamesAreTheArtifactTensorNames) {
  NetConfig cfg;
  cfg.hidden = {10, 20};
  Net net(16, cfg, HeadLayout{4, 1, UParam::kCholesky});
  EXPECT_EQ(net->DenseLayerNames(), (std::vector<std::string>{"mlp.0", "mlp.2", "head"}));
  std::vector<std::string> keys;
  for (const auto& p : net->named_parameters()) keys.push_back(p.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"mlp.0.weight", "mlp.0.bias", "mlp.2.weight",
                                            "mlp.2.bias", "head.weight", "head.bias"}));
  EXPECT_EQ(net->forward(torch::zeros({3, 16})).size(1),
            HeadLayout({4, 1, UParam::kCholesky}).Total());
}

}  // namespace
}  // namespace foresight::span
