// OtnetNet (thesis ch 6, the mixture density network): the mixture NLL against a direct
// double-precision evaluation of eq. lossF (and its log-domain form for far-away targets), its
// gradient against central differences, the layer layout and head split, the normalisation, the
// export against the torch-free engine, the task's gather, a tiny training run through the
// trainer, and errors.
#include "models/otnet/otnet_net.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <tuple>

#include "tests/test_util.h"
#include "training/otnet/task.h"
#include "training/trainer.h"

namespace foresight::otnet {
namespace {

using testing::ExpectErrorContains;
using testing::TempDir;

const auto kDouble = torch::TensorOptions().dtype(torch::kFloat64);

Eigen::MatrixXd ToEigen(const torch::Tensor& t) {
  const torch::Tensor c = t.detach().to(torch::kFloat64).contiguous().view({t.size(0), -1});
  Eigen::MatrixXd m(c.size(0), c.size(1));
  auto a = c.accessor<double, 2>();
  for (int i = 0; i < m.rows(); ++i)
    for (int j = 0; j < m.cols(); ++j) m(i, j) = a[i][j];
  return m;
}

torch::Tensor ToTorch(const Eigen::MatrixXd& m) {
  torch::Tensor t = torch::empty({m.rows(), m.cols()}, kDouble);
  auto a = t.accessor<double, 2>();
  for (int i = 0; i < m.rows(); ++i)
    for (int j = 0; j < m.cols(); ++j) a[i][j] = m(i, j);
  return t;
}

/// log p(w_j; mu, s) of one weight: Normal N(mu, s^2) or Laplace with scale s.
double LogDensity(double w, double mu, double s, MixtureFamily f) {
  if (f == MixtureFamily::kNormal)
    return -0.5 * std::pow((w - mu) / s, 2) - std::log(s) - 0.5 * std::log(2 * M_PI);
  return -std::abs(w - mu) / s - std::log(2 * s);
}

/// Row b of the mixture NLL straight from eq. lossF: -log sum_q alpha_q prod_j p_j, with alpha the
/// softmax of the logits. `log_domain` evaluates the same sum with a max shift (for targets whose
/// density underflows).
double DirectNll(const MixtureOutputs& out, const torch::Tensor& w, int b, MixtureFamily f,
                 bool log_domain) {
  const int q_count = static_cast<int>(out.logits.size(1));
  const int m2 = static_cast<int>(w.size(1));
  double z = 0;
  for (int q = 0; q < q_count; ++q) z += std::exp(out.logits[b][q].item<double>());
  std::vector<double> log_terms(q_count);
  double p = 0;
  for (int q = 0; q < q_count; ++q) {
    const double alpha = std::exp(out.logits[b][q].item<double>()) / z;
    double prod = 1, log_prod = 0;
    for (int j = 0; j < m2; ++j) {
      const double l = LogDensity(w[b][j].item<double>(), out.mean[b][q][j].item<double>(),
                                  std::exp(out.log_scale[b][q][j].item<double>()), f);
      prod *= std::exp(l);
      log_prod += l;
    }
    p += alpha * prod;
    log_terms[q] = std::log(alpha) + log_prod;
  }
  if (!log_domain) return -std::log(p);
  const double top = *std::max_element(log_terms.begin(), log_terms.end());
  double s = 0;
  for (double l : log_terms) s += std::exp(l - top);
  return -(top + std::log(s));
}

MixtureOutputs RandomOutputs(int b, int q, int m2, std::uint64_t seed) {
  torch::manual_seed(seed);
  MixtureOutputs o;
  o.logits = torch::randn({b, q}, kDouble);
  o.mean = torch::randn({b, q, m2}, kDouble);
  o.log_scale = torch::rand({b, q, m2}, kDouble) - 0.5;
  return o;
}

class MixtureNll : public ::testing::TestWithParam<std::tuple<MixtureFamily, int>> {};

TEST_P(MixtureNll, MatchesTheDirectFormulaAndStaysFiniteFarAway) {
  const auto [family, q] = GetParam();
  const int b = 6, m2 = 4;
  MixtureOutputs o = RandomOutputs(b, q, m2, 11 + q);
  torch::Tensor w = torch::randn({b, m2}, kDouble);
  // Rows 4 and 5 far away: the direct product underflows to 0 there (NLL = inf).
  o.log_scale[4].fill_(-3.0);
  w[4] = w[4] + 1e3;
  w[5] = w[5] - 5e2;
  const torch::Tensor nll = MixtureNegLogLikelihood(o, w, family);
  ASSERT_EQ(nll.sizes(), torch::IntArrayRef({b}));
  for (int r = 0; r < 4; ++r)
    EXPECT_NEAR(nll[r].item<double>(), DirectNll(o, w, r, family, false),
                1e-12 * (1 + std::abs(nll[r].item<double>())))
        << "row " << r;
  for (int r = 4; r < 6; ++r) {
    EXPECT_TRUE(std::isinf(DirectNll(o, w, r, family, false))) << "row " << r;
    const double ref = DirectNll(o, w, r, family, true);
    EXPECT_GT(ref, 1e3);
    EXPECT_NEAR(nll[r].item<double>(), ref, 1e-12 * ref) << "row " << r;
  }
  // The same far targets in float32 (the training precision) stay finite and accurate.
  MixtureOutputs of{o.logits.to(torch::kFloat32), o.mean.to(torch::kFloat32),
                    o.log_scale.to(torch::kFloat32)};
  const torch::Tensor nll_f = MixtureNegLogLikelihood(of, w.to(torch::kFloat32), family);
  EXPECT_TRUE(torch::isfinite(nll_f).all().item<bool>());
  for (int r = 0; r < b; ++r)
    EXPECT_NEAR(nll_f[r].item<double>(), nll[r].item<double>(),
                1e-5 * (1 + std::abs(nll[r].item<double>())))
        << "row " << r;
}

TEST_P(MixtureNll, GradientMatchesCentralDifferences) {
  const auto [family, q] = GetParam();
  const int b = 3, m2 = 4;
  MixtureOutputs o = RandomOutputs(b, q, m2, 21 + q);
  // Keep targets away from the means so that |w - mu| (Laplace) is smooth within the step.
  const torch::Tensor w = o.mean.select(1, 0) + 0.3 + torch::rand({b, m2}, kDouble);
  const torch::Tensor c = torch::rand({b}, kDouble) + 0.5;  // a generic linear functional of NLL
  for (torch::Tensor* t : {&o.logits, &o.mean, &o.log_scale}) t->requires_grad_(true);
  const torch::Tensor f = (MixtureNegLogLikelihood(o, w, family) * c).sum();
  const auto grads = torch::autograd::grad({f}, {o.logits, o.mean, o.log_scale});
  torch::NoGradGuard no_grad;
  const double h = 1e-6;
  const char* names[] = {"logits", "mean", "log_scale"};
  torch::Tensor* leaves[] = {&o.logits, &o.mean, &o.log_scale};
  for (int k = 0; k < 3; ++k) {
    const torch::Tensor flat = leaves[k]->view({-1});
    const torch::Tensor g = grads[k].reshape({-1});
    for (int i = 0; i < flat.numel(); ++i) {
      const double x0 = flat[i].item<double>();
      flat[i] = x0 + h;
      const double up = (MixtureNegLogLikelihood(o, w, family) * c).sum().item<double>();
      flat[i] = x0 - h;
      const double down = (MixtureNegLogLikelihood(o, w, family) * c).sum().item<double>();
      flat[i] = x0;
      const double fd = (up - down) / (2 * h);
      EXPECT_NEAR(g[i].item<double>(), fd, 1e-6 * (1 + std::abs(fd)))
          << names[k] << "[" << i << "]";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(FamiliesAndComponents, MixtureNll,
                         ::testing::Combine(::testing::Values(MixtureFamily::kNormal,
                                                              MixtureFamily::kLaplace),
                                            ::testing::Values(1, 3)));

OtnetNetOptions SmallOptions() {
  OtnetNetOptions o;
  o.inputs = 5;
  o.hidden = {7, 6};
  o.components = 2;
  o.weights = 4;
  return o;
}

TEST(OtnetNet, LayersAreNamedAndForwardIsTheReluMlp) {
  torch::manual_seed(3);
  OtnetNet net(SmallOptions());
  const auto params = net->named_parameters();
  ASSERT_EQ(params.size(), 6u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(params.contains("layer" + std::to_string(i) + ".weight"));
    EXPECT_TRUE(params.contains("layer" + std::to_string(i) + ".bias"));
    EXPECT_EQ(params["layer" + std::to_string(i) + ".weight"].scalar_type(), torch::kFloat32);
  }
  EXPECT_EQ(params["layer2.weight"].size(0), (OtnetHead{2, 4}.Total()));
  // Reference in double: relu(W0 x + b0) -> relu(W1 . + b1) -> W2 . + b2.
  const torch::Tensor x = torch::randn({4, 5}, kDouble);
  torch::Tensor h = x;
  for (int i = 0; i < 3; ++i) {
    const std::string n = "layer" + std::to_string(i);
    h = torch::matmul(h, params[n + ".weight"].to(torch::kFloat64).t()) +
        params[n + ".bias"].to(torch::kFloat64);
    if (i < 2) h = h.clamp_min(0);
  }
  torch::NoGradGuard no_grad;
  const torch::Tensor y = net->forward(x);
  EXPECT_EQ(y.scalar_type(), torch::kFloat32);
  EXPECT_LT((y.to(torch::kFloat64) - h).abs().max().item<double>(), 1e-5);
}

TEST(OtnetNet, InitialisationIsDeterministicAndStartsTheComponentsApart) {
  OtnetNetOptions o = SmallOptions();
  o.components = 4;
  o.weights = 6;
  torch::manual_seed(5);
  OtnetNet a(o);
  torch::manual_seed(5);
  OtnetNet b(o);
  torch::manual_seed(6);
  OtnetNet c(o);
  const auto pa = a->named_parameters(), pb = b->named_parameters(), pc = c->named_parameters();
  bool all_equal = true, any_differs = false;
  for (const auto& p : pa) {
    all_equal = all_equal && torch::equal(p.value(), pb[p.key()]);
    any_differs = any_differs || !torch::equal(p.value(), pc[p.key()]);
  }
  EXPECT_TRUE(all_equal);
  EXPECT_TRUE(any_differs);
  // Head bias: logits 0 (uniform alpha), log-scales 0, means spread (std ~ 1) and distinct.
  const OtnetHead head{4, 6};
  const torch::Tensor bias = pa["layer2.bias"].to(torch::kFloat64);
  EXPECT_EQ(bias.narrow(0, 0, 4).abs().max().item<double>(), 0.0);
  EXPECT_EQ(bias.narrow(0, head.LogScaleOffset(0), 24).abs().max().item<double>(), 0.0);
  const torch::Tensor means = bias.narrow(0, head.MeanOffset(0), 24).view({4, 6});
  EXPECT_GT(means.std().item<double>(), 0.4);
  EXPECT_LT(means.std().item<double>(), 2.0);
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      EXPECT_GT((means[i] - means[j]).norm().item<double>(), 0.5) << i << ", " << j;
}

TEST(OtnetNet, SplitFollowsTheHeadLayoutAndClampsLogScales) {
  OtnetNet net(SmallOptions());
  const OtnetHead head{2, 4};
  torch::Tensor raw = torch::arange(2 * head.Total(), kDouble).view({2, head.Total()}) * 0.1;
  raw[1][head.LogScaleOffset(1) + 2] = 100.0;
  raw[1][head.LogScaleOffset(0)] = -100.0;
  const MixtureOutputs o = net->Split(raw);
  ASSERT_EQ(o.logits.sizes(), torch::IntArrayRef({2, 2}));
  ASSERT_EQ(o.mean.sizes(), torch::IntArrayRef({2, 2, 4}));
  ASSERT_EQ(o.log_scale.sizes(), torch::IntArrayRef({2, 2, 4}));
  for (int b = 0; b < 2; ++b)
    for (int q = 0; q < 2; ++q) {
      EXPECT_EQ(o.logits[b][q].item<double>(), raw[b][q].item<double>());
      for (int j = 0; j < 4; ++j) {
        EXPECT_EQ(o.mean[b][q][j].item<double>(), raw[b][head.MeanOffset(q) + j].item<double>());
        const double r = raw[b][head.LogScaleOffset(q) + j].item<double>();
        EXPECT_EQ(o.log_scale[b][q][j].item<double>(),
                  std::clamp(r, OtnetHead::kLogScaleMin, OtnetHead::kLogScaleMax));
      }
    }
  EXPECT_EQ(o.log_scale[1][1][2].item<double>(), OtnetHead::kLogScaleMax);
  EXPECT_EQ(o.log_scale[1][0][0].item<double>(), OtnetHead::kLogScaleMin);
}

TEST(OtnetNet, DropoutActsOnlyInTrainingMode) {
  OtnetNetOptions o = SmallOptions();
  o.hidden = {64};
  o.dropout = 0.5;
  torch::manual_seed(8);
  OtnetNet net(o);
  torch::NoGradGuard no_grad;
  const torch::Tensor x = torch::randn({3, 5});
  net->train();
  EXPECT_FALSE(torch::equal(net->forward(x), net->forward(x)));
  net->eval();
  EXPECT_TRUE(torch::equal(net->forward(x), net->forward(x)));
}

TEST(OtnetNormalisation, FitIsTheColumnMeanAndPopulationStd) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n(0, 1);
  Eigen::MatrixXd phi(7, 3), w(20, 4);
  for (double& v : phi.reshaped()) v = 2 + n(rng);
  for (double& v : w.reshaped()) v = -1 + 3 * n(rng);
  w.col(2).setConstant(4.5);  // a constant column: std floored at 1e-6
  const OtnetNormalisation norm = OtnetNormalisation::Fit(phi, w);
  const auto check = [](const Eigen::MatrixXd& x, const Eigen::VectorXd& mean,
                        const Eigen::VectorXd& std) {
    ASSERT_EQ(mean.size(), x.cols());
    ASSERT_EQ(std.size(), x.cols());
    for (int j = 0; j < x.cols(); ++j) {
      double s = 0, ss = 0;
      for (int i = 0; i < x.rows(); ++i) s += x(i, j);
      const double m = s / static_cast<double>(x.rows());
      for (int i = 0; i < x.rows(); ++i) ss += (x(i, j) - m) * (x(i, j) - m);
      EXPECT_NEAR(mean[j], m, 1e-12);
      EXPECT_NEAR(std[j], std::max(1e-6, std::sqrt(ss / static_cast<double>(x.rows()))), 1e-12);
    }
  };
  check(phi, norm.input_mean, norm.input_std);
  check(w, norm.weight_mean, norm.weight_std);
  EXPECT_EQ(norm.weight_std[2], 1e-6);
}

BinaryGrid WalledGrid() {
  BinaryGrid g(40, 40);
  for (int i = 0; i < 40; ++i) g.at(0, i) = g.at(39, i) = g.at(i, 0) = g.at(i, 39) = 1;
  return g;
}

MapEncoder ThreeMapEncoder() {
  BinaryGrid a = WalledGrid(), b = WalledGrid(), c = WalledGrid();
  for (int r = 0; r < 26; ++r) a.at(r, 20) = 1;           // a vertical wall from the top
  for (int col = 10; col < 40; ++col) b.at(15, col) = 1;  // a horizontal wall from the right
  for (int r = 25; r <= 30; ++r)
    for (int col = 5; col <= 15; ++col) c.at(r, col) = 1;  // a block
  return MapEncoder({a, b, c}, 50.0);
}

TEST(ExportMlp, TheEngineReproducesTheNetOnRawPhi) {
  const MapEncoder encoder = ThreeMapEncoder();
  const TrajectoryBasis basis(6, 50, 1e-6);
  OtnetNormalisation norm;
  norm.input_mean = Eigen::Vector3d(0.4, 0.5, 0.6);
  norm.input_std = Eigen::Vector3d(0.2, 0.3, 0.1);
  norm.weight_mean = Eigen::VectorXd::LinSpaced(12, -10, 20);
  norm.weight_std = Eigen::VectorXd::LinSpaced(12, 0.5, 3);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0, 1);
  for (MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    OtnetNetOptions o;
    o.inputs = 3;
    o.hidden = {16, 8};
    o.components = 3;
    o.weights = basis.weights();
    o.family = family;
    torch::manual_seed(family == MixtureFamily::kNormal ? 1 : 2);
    OtnetNet net(o);
    {  // Head weights large enough that alpha, means and scales depend visibly on phi.
      torch::NoGradGuard no_grad;
      net->linears().back()->weight.copy_(0.4 * torch::randn({o.components * 25, 8}));
    }
    const OtnetModel model(encoder, basis, ExportMlp(net, norm), family, 3);
    OtnetModel::Workspace ws = model.MakeWorkspace();
    Mixture mixture;
    double alpha_spread = 0;
    for (int trial = 0; trial < 10; ++trial) {
      Eigen::VectorXd phi(3);
      if (trial == 0) {
        MapEncoder::Workspace ew = encoder.MakeWorkspace();
        encoder.Encode(encoder.database()[1], &ew, phi);  // a real encoding
      } else {
        for (double& v : phi) v = u(rng);
      }
      model.PredictFromFeatures(phi, &ws, &mixture);
      // The net on standardised phi, de-standardised by hand.
      torch::NoGradGuard no_grad;
      const Eigen::MatrixXd phi_hat =
          (phi - norm.input_mean).cwiseQuotient(norm.input_std).transpose();
      const MixtureOutputs out = net->Split(net->forward(ToTorch(phi_hat)));
      const Eigen::MatrixXd alpha = ToEigen(torch::softmax(out.logits.to(torch::kFloat64), 1));
      const Eigen::MatrixXd mean_hat = ToEigen(out.mean[0]), log_s_hat = ToEigen(out.log_scale[0]);
      ASSERT_EQ(mixture.components(), 3);
      ASSERT_EQ(mixture.mean.rows(), 3);
      ASSERT_EQ(mixture.mean.cols(), 12);
      EXPECT_EQ(mixture.family, family);
      EXPECT_FALSE(mixture.conditioned);
      for (int q = 0; q < 3; ++q) {
        EXPECT_NEAR(mixture.alpha[q], alpha(0, q), 1e-5 * alpha(0, q)) << trial << " q " << q;
        for (int j = 0; j < 12; ++j) {
          const double mean = mean_hat(q, j) * norm.weight_std[j] + norm.weight_mean[j];
          const double scale = std::exp(log_s_hat(q, j) + std::log(norm.weight_std[j]));
          EXPECT_NEAR(mixture.mean(q, j), mean, 1e-5 * (std::abs(mean) + norm.weight_std[j]))
              << trial << " q " << q << " j " << j;
          EXPECT_NEAR(mixture.scale(q, j), scale, 1e-5 * scale)
              << trial << " q " << q << " j " << j;
        }
      }
      alpha_spread = std::max(alpha_spread, alpha.maxCoeff() - alpha.minCoeff());
    }
    EXPECT_GT(alpha_spread, 0.05);  // the comparison is not between near-constant outputs
  }
}

/// Two groups of maps (phi near one of two prototypes); each group's trajectories fall in two
/// clusters of w. Returns raw phi [maps x D], map index per trajectory and raw w [N x 4].
// Where the log-scale clamp is active (a collapsed component), the engine with the export's
// log-scale offset clamps in the standardised space, as training does.
TEST(ExportMlp, TheEngineClampsTheLogScaleWhereTrainingDid) {
  const MapEncoder encoder = ThreeMapEncoder();
  const TrajectoryBasis basis(6, 50, 1e-6);
  OtnetNormalisation norm;
  norm.input_mean = Eigen::Vector3d::Zero();
  norm.input_std = Eigen::Vector3d::Ones();
  norm.weight_mean = Eigen::VectorXd::Zero(12);
  norm.weight_std = Eigen::VectorXd::LinSpaced(12, 2, 30);
  OtnetNetOptions o;
  o.inputs = 3;
  o.hidden = {8};
  o.components = 2;
  o.weights = basis.weights();
  torch::manual_seed(3);
  OtnetNet net(o);
  {  // Log-scale biases far outside [-7, 7] in both directions.
    torch::NoGradGuard no_grad;
    auto bias = net->linears().back()->bias;
    const OtnetHead head{o.components, o.weights};
    for (int q = 0; q < o.components; ++q)
      for (int j = 0; j < o.weights; ++j)
        bias[head.LogScaleOffset(q) + j] = (j % 2 ? 20.0f : -20.0f);
    net->linears().back()->weight.zero_();
  }
  OtnetModel model(encoder, basis, ExportMlp(net, norm), MixtureFamily::kNormal, 2);
  model.SetLogScaleOffset(norm.weight_std.array().log().matrix());
  OtnetModel::Workspace ws = model.MakeWorkspace();
  Mixture mixture;
  model.PredictFromFeatures(Eigen::Vector3d(0.3, 0.2, 0.9), &ws, &mixture);
  for (int q = 0; q < 2; ++q)
    for (int j = 0; j < 12; ++j) {
      const double trained =
          std::exp(j % 2 ? OtnetHead::kLogScaleMax : OtnetHead::kLogScaleMin) * norm.weight_std[j];
      EXPECT_NEAR(mixture.scale(q, j) / trained, 1.0, 1e-5) << q << " " << j;
    }
}

struct Synthetic {
  Eigen::MatrixXd phi;
  std::vector<std::int64_t> map;
  Eigen::MatrixXd w;
  std::vector<int> group;  // per map
};

const double kClusters[2][2][4] = {{{2, 2, -1, 0}, {-2, 1, 1, 2}},
                                   {{0, -2, 2, -1}, {1, 0, -2, -2}}};

Synthetic MakeSynthetic(int maps, int per_map, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  const Eigen::VectorXd proto[2] = {
      (Eigen::VectorXd(6) << 0.9, 0.8, 0.7, 0.1, 0.2, 0.1).finished(),
      (Eigen::VectorXd(6) << 0.1, 0.2, 0.1, 0.7, 0.8, 0.9).finished()};
  Synthetic s;
  s.phi.resize(maps, 6);
  s.w.resize(maps * per_map, 4);
  for (int m = 0; m < maps; ++m) {
    const int g = m % 2;
    s.group.push_back(g);
    for (int d = 0; d < 6; ++d) s.phi(m, d) = proto[g][d] + 0.05 * n(rng);
    for (int t = 0; t < per_map; ++t) {
      const int c = (t + m / 2) % 2;
      const int row = m * per_map + t;
      s.map.push_back(m);
      for (int j = 0; j < 4; ++j) s.w(row, j) = kClusters[g][c][j] + 0.15 * n(rng);
    }
  }
  return s;
}

torch::Tensor Standardised(const Eigen::MatrixXd& x, const Eigen::VectorXd& mean,
                           const Eigen::VectorXd& std) {
  return ToTorch((x.rowwise() - mean.transpose()).array().rowwise() / std.transpose().array())
      .to(torch::kFloat32);
}

torch::Tensor Longs(const std::vector<std::int64_t>& v) {
  return torch::tensor(v, torch::TensorOptions().dtype(torch::kInt64));
}

TEST(OtnetTask, BatchLossGathersPhiByMapAndDividesBy2M) {
  const Synthetic s = MakeSynthetic(4, 5, 1);
  OtnetNetOptions o;
  o.inputs = 6;
  o.hidden = {8};
  o.components = 2;
  o.weights = 4;
  o.family = MixtureFamily::kLaplace;
  o.dropout = 0.3;
  torch::manual_seed(2);
  OtnetNet net(o);
  const torch::Tensor phi = ToTorch(s.phi).to(torch::kFloat32), w = ToTorch(s.w);
  OtnetTask task(net, phi, Longs(s.map), w, phi, Longs(s.map), w);
  EXPECT_EQ(task.num_train(), 20);
  net->eval();  // deterministic for the comparison
  const std::vector<std::int64_t> idx = {3, 17, 0, 11};
  const double loss = task.BatchLoss(Longs(idx)).item<double>();
  double ref = 0;
  for (std::int64_t i : idx) {
    const torch::Tensor p = phi[s.map[static_cast<std::size_t>(i)]].unsqueeze(0);
    ref += MixtureNegLogLikelihood(net->Split(net->forward(p)), w[i].unsqueeze(0),
                                   MixtureFamily::kLaplace)
               .item<double>();
  }
  EXPECT_NEAR(loss, ref / 4 / 4, 1e-6 * (1 + std::abs(loss)));
  // Validation: every row, in eval mode (deterministic with dropout), the mode restored after.
  net->train();
  const double v1 = task.ValidationLoss();
  EXPECT_TRUE(net->is_training());
  const double v2 = task.ValidationLoss();
  EXPECT_EQ(v1, v2);
  net->eval();
  const double all = task.BatchLoss(torch::arange(20, torch::kInt64)).item<double>();
  EXPECT_NEAR(v1, all, 1e-6 * (1 + std::abs(all)));
  EXPECT_FALSE(net->is_training());
}

TEST(OtnetTask, TrainingLearnsTheMapDependentClusters) {
  const Synthetic train = MakeSynthetic(8, 50, 5), val = MakeSynthetic(2, 50, 6);
  const OtnetNormalisation norm = OtnetNormalisation::Fit(train.phi, train.w);
  OtnetNetOptions o;
  o.inputs = 6;
  o.hidden = {32, 32};
  o.components = 2;
  o.weights = 4;
  torch::manual_seed(0);
  OtnetNet net(o);
  OtnetTask task(net, Standardised(train.phi, norm.input_mean, norm.input_std), Longs(train.map),
                 Standardised(train.w, norm.weight_mean, norm.weight_std),
                 Standardised(val.phi, norm.input_mean, norm.input_std), Longs(val.map),
                 Standardised(val.w, norm.weight_mean, norm.weight_std));
  const double before = task.ValidationLoss();
  TrainConfig c;
  c.epochs = 60;
  c.batch_size = 50;
  c.learning_rate = 1e-2;
  c.schedule = LrSchedule::kCosine;
  c.patience = 0;
  c.progress = ProgressStyle::kNone;
  TempDir dir;
  const TrainingSummary summary = Train(&task, c, RunPaths{dir.File("run")}, 1, false);
  EXPECT_EQ(summary.reason, TerminationReason::kMaxEpochs) << summary.BriefReport();
  const double after = task.ValidationLoss();
  // Per weight dimension: a standard normal fit gives ~1.42; clusters of std ~0.1 (standardised)
  // and two equal components give ~ log(0.1 sqrt(2 pi e)) + log(2) / 4 ~ -0.7.
  EXPECT_GT(before, 1.0);
  EXPECT_LT(after, before - 1.5) << "before " << before << ", after " << after;
  EXPECT_LT(after, 0.0);

  // On each (unseen) validation map both of its group's clusters carry a component nearby.
  net->eval();
  torch::NoGradGuard no_grad;
  const MixtureOutputs out =
      net->Split(net->forward(Standardised(val.phi, norm.input_mean, norm.input_std)));
  const Eigen::MatrixXd alpha = ToEigen(torch::softmax(out.logits, 1));
  for (int m = 0; m < 2; ++m) {
    const Eigen::MatrixXd mean_hat = ToEigen(out.mean[m]);  // [Q x 4]
    for (int cl = 0; cl < 2; ++cl) {
      double best = 1e9;
      for (int q = 0; q < 2; ++q) {
        if (alpha(m, q) < 0.25) continue;
        double d2 = 0;
        for (int j = 0; j < 4; ++j) {
          const double mu = mean_hat(q, j) * norm.weight_std[j] + norm.weight_mean[j];
          d2 += std::pow(mu - kClusters[val.group[m]][cl][j], 2);
        }
        best = std::min(best, std::sqrt(d2));
      }
      EXPECT_LT(best, 0.5) << "map " << m << " (group " << val.group[m] << ") cluster " << cl;
    }
  }
}

TEST(OtnetNet, BadOptionsAndShapesAreErrors) {
  const auto bad = [](const std::function<void(OtnetNetOptions*)>& edit,
                      const std::vector<std::string>& parts) {
    OtnetNetOptions o = SmallOptions();
    edit(&o);
    ExpectErrorContains([&] { OtnetNet{o}; }, parts);
  };
  bad([](OtnetNetOptions* o) { o->inputs = 0; }, {"inputs", "0"});
  bad([](OtnetNetOptions* o) { o->hidden.clear(); }, {"hidden"});
  bad([](OtnetNetOptions* o) { o->hidden = {4, 0}; }, {"hidden[1]", "0"});
  bad([](OtnetNetOptions* o) { o->components = 0; }, {"components", "0"});
  bad([](OtnetNetOptions* o) { o->weights = 3; }, {"weights", "3"});
  bad([](OtnetNetOptions* o) { o->weights = 0; }, {"weights", "0"});
  bad([](OtnetNetOptions* o) { o->dropout = 1.0; }, {"dropout", "1"});
  bad([](OtnetNetOptions* o) { o->dropout = -0.1; }, {"dropout", "-0.1"});

  OtnetNet net(SmallOptions());
  ExpectErrorContains([&] { net->forward(torch::zeros({2, 4})); }, {"phi", "[B, 5]", "[2, 4]"});
  ExpectErrorContains([&] { net->Split(torch::zeros({2, 7})); }, {"raw", "[2, 7]"});
  const MixtureOutputs o = net->Split(torch::zeros({2, OtnetHead{2, 4}.Total()}));
  ExpectErrorContains(
      [&] {
        MixtureNegLogLikelihood(o, torch::zeros({2, 5}), MixtureFamily::kNormal);
      },
      {"mean", "[2, 2, 5]"});
  ExpectErrorContains(
      [&] {
        MixtureNegLogLikelihood(o, torch::zeros({3, 4}), MixtureFamily::kNormal);
      },
      {"w", "[3, 4]"});

  OtnetNormalisation norm;
  norm.input_mean = norm.input_std = Eigen::VectorXd::Ones(4);
  norm.weight_mean = norm.weight_std = Eigen::VectorXd::Ones(4);
  ExpectErrorContains([&] { ExportMlp(net, norm); }, {"input", "4", "5 inputs"});
  norm.input_mean = norm.input_std = Eigen::VectorXd::Ones(5);
  norm.weight_std[1] = 0;
  ExpectErrorContains([&] { ExportMlp(net, norm); }, {"stds > 0"});
  ExpectErrorContains(
      [&] { OtnetNormalisation::Fit(Eigen::MatrixXd(0, 3), Eigen::MatrixXd(2, 2)); },
      {"phi", "0 x 3"});
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(2, 2);
  w(1, 1) = NAN;
  ExpectErrorContains([&] { OtnetNormalisation::Fit(Eigen::MatrixXd::Zero(2, 3), w); },
                      {"w", "non-finite"});
}

TEST(OtnetTask, InconsistentTensorsAreErrors) {
  OtnetNet net(SmallOptions());  // 5 inputs, 4 weights
  const torch::Tensor phi = torch::zeros({3, 5}), map = Longs({0, 2, 1, 1}),
                      w = torch::zeros({4, 4});
  const auto task = [&](torch::Tensor p, torch::Tensor m, torch::Tensor ww, torch::Tensor pv,
                        torch::Tensor mv, torch::Tensor wv) {
    return [=] { OtnetTask t(net, p, m, ww, pv, mv, wv); };
  };
  EXPECT_NO_THROW(task(phi, map, w, phi, map, w)());
  ExpectErrorContains(task(torch::zeros({3, 6}), map, w, phi, map, w), {"phi_train", "[3, 6]"});
  ExpectErrorContains(task(phi, map, w, phi, map, torch::zeros({4, 3})), {"w_val", "[4, 3]"});
  ExpectErrorContains(task(phi, Longs({0, 1, 2}), w, phi, map, w), {"map_train", "[3]"});
  ExpectErrorContains(task(phi, map, w, phi, Longs({0, 1, 3, 0}), w),
                      {"map_val", "[0, 3]", "3 rows"});
  ExpectErrorContains(task(phi, Longs({0, -1, 0, 0}), w, phi, map, w), {"map_train", "-1"});
  ExpectErrorContains(task(phi, torch::zeros({4}), w, phi, map, w), {"map_train", "integer"});
  torch::Tensor w_nan = w.clone();
  w_nan[2][1] = NAN;
  ExpectErrorContains(task(phi, map, w_nan, phi, map, w), {"w_train", "non-finite"});
  ExpectErrorContains(task(phi, map, w, torch::zeros({0, 5}), Longs({}), torch::zeros({0, 4})),
                      {"phi_val", "maps >= 1"});
}

}  // namespace
}  // namespace foresight::otnet
