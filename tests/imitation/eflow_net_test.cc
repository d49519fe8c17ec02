// EFlowNet: the analytic Jacobian against autograd, each coupling layer against an independent
// evaluation of its formula and its exact inverse, training on an analytic arc (through the
// trainer), and the exported engine (after a save/load round trip) against the net.
#include "models/imitation/eflow_net.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/test_util.h"
#include "training/diffeo/imitation_task.h"
#include "training/trainer.h"

namespace foresight::imitation {
namespace {

using testing::ExpectErrorContains;
using testing::TempDir;

EFlowNet RandomNet(int d, std::uint64_t seed) {
  EFlowNetOptions o;
  o.dimension = d;
  o.layers = 5;
  o.features = 24;
  o.bandwidth = 1.5;
  o.initial_speed = 0.7;
  o.seed = seed;
  EFlowNet net(o);
  torch::manual_seed(seed);
  torch::NoGradGuard no_grad;
  for (auto& p : net->named_parameters())
    if (p.key() != "log_speed") p.value().copy_(0.3 * torch::randn(p.value().sizes(), kDouble));
  return net;
}

torch::Tensor RandomPoints(int n, int d, std::uint64_t seed) {
  torch::manual_seed(seed);
  return torch::rand({n, d}, kDouble) * 2 - 1;
}

class EFlowNetDims : public ::testing::TestWithParam<int> {};

TEST_P(EFlowNetDims, JacobianMatchesAutograd) {
  const int d = GetParam();
  EFlowNet net = RandomNet(d, 1 + d);
  const torch::Tensor x = RandomPoints(6, d, 2).requires_grad_(true);
  auto [z, j] = net->Forward(x);
  for (int i = 0; i < d; ++i) {
    const torch::Tensor row =
        torch::autograd::grad({z.select(1, i).sum()}, {x}, {}, /*retain_graph=*/true)[0];
    EXPECT_LT((row - j.select(1, i)).abs().max().item<double>(), 1e-12) << "row " << i;
  }
  EXPECT_GT((j - torch::eye(d, kDouble)).abs().max().item<double>(), 0.05);
}

TEST_P(EFlowNetDims, EachLayerIsTheCouplingFormulaAndInvertsExactly) {
  const int d = GetParam();
  EFlowNet net = RandomNet(d, 10 + d);
  torch::NoGradGuard no_grad;
  const torch::Tensor x = RandomPoints(7, d, 3);
  auto params = net->named_parameters();
  auto buffers = net->named_buffers();
  for (int l = 0; l < net->num_layers(); ++l) {
    const std::string n = std::to_string(l);
    const int b = l % d;
    // Independent evaluation: y_b = x_b exp(sigma' r) + tau' r, r = sqrt(2/F) cos(Omega x_a +
    // beta).
    std::vector<std::int64_t> fixed;
    for (int c = 0; c < d; ++c)
      if (c != b) fixed.push_back(c);
    const torch::Tensor xa = x.index_select(1, torch::tensor(fixed, torch::kInt64));
    const torch::Tensor r =
        std::sqrt(2.0 / 24) *
        torch::cos(torch::matmul(xa, buffers["omega" + n].t()) + buffers["phase" + n]);
    const torch::Tensor yb = x.select(1, b) * torch::exp(torch::matmul(r, params["scale" + n])) +
                             torch::matmul(r, params["translate" + n]);
    const torch::Tensor y = net->ForwardLayer(l, x);
    EXPECT_LT((y.select(1, b) - yb).abs().max().item<double>(), 1e-14) << "layer " << l;
    EXPECT_TRUE(torch::equal(y.index_select(1, torch::tensor(fixed, torch::kInt64)), xa));
    EXPECT_GT((y - x).abs().max().item<double>(), 1e-3);
    EXPECT_LT((net->InverseLayer(l, y) - x).abs().max().item<double>(), 1e-14);
    EXPECT_LT((net->ForwardLayer(l, net->InverseLayer(l, x)) - x).abs().max().item<double>(),
              1e-14);
  }
  EXPECT_LT((net->Inverse(net->Map(x)) - x).abs().max().item<double>(), 1e-12);
}

TEST_P(EFlowNetDims, EngineEqualsTheNetAfterASaveLoadRoundTrip) {
  const int d = GetParam();
  EFlowNet net = RandomNet(d, 20 + d);
  const Eigen::VectorXd goal = Eigen::VectorXd::LinSpaced(d, -0.2, 0.3);
  TempDir dir;
  const std::string path = dir.File("eflow.h5");
  net->ToEngine(goal).Save(path, "", 5);
  const EFlowModel engine = EFlowModel::Load(path);
  EXPECT_NEAR(engine.speed(), 0.7, 1e-15);

  torch::NoGradGuard no_grad;
  const torch::Tensor x = RandomPoints(20, d, 4);
  auto [z, j] = net->Forward(x);
  const torch::Tensor v =
      net->Velocity(x, torch::from_blob(const_cast<double*>(goal.data()), {d}, kDouble));
  const torch::Tensor xi = net->Inverse(x);
  for (int b = 0; b < 20; ++b) {
    Eigen::VectorXd xb(d);
    for (int i = 0; i < d; ++i) xb[i] = x[b][i].item<double>();
    Eigen::MatrixXd jb;
    const Eigen::VectorXd zb = engine.Forward(xb, &jb);
    const Eigen::VectorXd vb = engine.Velocity(xb);
    const Eigen::VectorXd ib = engine.Inverse(xb);
    for (int i = 0; i < d; ++i) {
      EXPECT_NEAR(zb[i], z[b][i].item<double>(), 1e-12);
      EXPECT_NEAR(vb[i], v[b][i].item<double>(), 1e-12);
      EXPECT_NEAR(ib[i], xi[b][i].item<double>(), 1e-12);
      for (int k = 0; k < d; ++k) EXPECT_NEAR(jb(i, k), j[b][i][k].item<double>(), 1e-12);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Dimensions, EFlowNetDims, ::testing::Values(2, 3));

TEST(EFlowNet, VelocityAtTheGoalIsZeroWithFiniteGradients) {
  EFlowNet net = RandomNet(2, 30);
  const torch::Tensor goal = torch::tensor({0.25, -0.3}, kDouble);
  const torch::Tensor v = net->Velocity(torch::stack({goal, goal + 0.5}), goal);
  EXPECT_LE(v[0].abs().max().item<double>(), 1e-6);  // kGoalEpsilon: rounding-level z - z_e
  EXPECT_GT(v[1].norm().item<double>(), 0.1);
  VelocityLoss(v, torch::ones({2, 2}, kDouble)).backward();
  for (const auto& p : net->parameters()) EXPECT_TRUE(torch::isfinite(p.grad()).all().item<bool>());
}

TEST(EFlowNet, TrainingThroughTheTrainerLowersTheValidationLoss) {
  // A quarter circle of radius 1 ending at the origin at unit speed (as in flow_net_test.cc).
  const auto arc = [](int n, double offset, torch::Tensor* p, torch::Tensor* v) {
    const torch::Tensor theta = (M_PI / 2) * (torch::arange(n, kDouble) + offset) / n;
    *p = torch::stack({torch::sin(theta), 1 - torch::cos(theta)}, 1);
    *v = -torch::stack({torch::cos(theta), torch::sin(theta)}, 1);
  };
  torch::Tensor p, v, pv, vv;
  arc(40, 0.25, &p, &v);
  arc(15, 0.6, &pv, &vv);
  EFlowNetOptions o;
  o.layers = 6;
  o.features = 40;
  o.bandwidth = 2;
  o.seed = 3;
  auto net = std::make_shared<EFlowNetImpl>(o);
  ImitationTask task(net, p, v, pv, vv, torch::zeros({2}, kDouble));
  const double before = task.ValidationLoss();
  TrainConfig c;
  c.epochs = 40;
  c.batch_size = 40;
  c.learning_rate = 0.03;
  c.schedule = LrSchedule::kConstant;
  c.patience = 0;
  c.progress = ProgressStyle::kNone;
  TempDir dir;
  const TrainingSummary s = Train(&task, c, RunPaths{dir.File("run")}, 1, false);
  EXPECT_EQ(s.reason, TerminationReason::kMaxEpochs) << s.BriefReport();
  const double after = task.ValidationLoss();
  EXPECT_GT(before, 0.05);
  EXPECT_LT(after, before / 10) << "before " << before << ", after " << after;
}

TEST(EFlowNet, BadOptionsAreErrors) {
  EFlowNetOptions o;
  o.dimension = 1;
  ExpectErrorContains([&] { EFlowNet{o}; }, {"dimension", "1"});
  o = {};
  o.bandwidth = 0;
  ExpectErrorContains([&] { EFlowNet{o}; }, {"bandwidth"});
  o = {};
  o.layers = 0;
  ExpectErrorContains([&] { EFlowNet{o}; }, {"layers"});
  EFlowNet net(EFlowNetOptions{});
  ExpectErrorContains([&] { net->ForwardLayer(10, torch::zeros({1, 2}, kDouble)); }, {"layer 10"});
  ExpectErrorContains(
      [&] {
        net->Velocity(torch::zeros({1, 2}, kDouble), torch::zeros({3}));
      },
      {"goal"});
}

}  // namespace
}  // namespace foresight::imitation
