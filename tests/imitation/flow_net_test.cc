// RbfFlowNet: the explicit variational Jacobian against autograd and central differences, the
// loss gradient against finite differences, the goal, a short training on an analytic arc, and
// (with the engine library) parity with RbfFlow / ImitationSystem.
#include "models/imitation/flow_net.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "inference/imitation/rbf_grid.h"
#include "models/imitation/flow_objective.h"
#include "tests/test_util.h"
#include "training/diffeo/imitation_task.h"
#ifdef FORESIGHT_HAVE_RBF_FLOW_ENGINE
#include "inference/imitation/rbf_flow.h"
#endif

namespace foresight::imitation {
namespace {

using testing::ExpectErrorContains;

/// Centres of a regular grid over [lo, hi]^2 with n per axis, in RbfGrid order (x fastest).
torch::Tensor GridCentres(double lo, double hi, int n) {
  torch::Tensor c = torch::empty({n * n, 2}, kDouble);
  const double spacing = (hi - lo) / (n - 1);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      c[j * n + i][0] = lo + spacing * i;
      c[j * n + i][1] = lo + spacing * j;
    }
  return c;
}

/// A net on a 6 x 6 grid over [-1, 1]^2 with random weights (a clearly non-linear psi).
RbfFlowNet RandomNet(std::uint64_t seed, int steps = 8, int segments = 1) {
  RbfFlowNet net(GridCentres(-1, 1, 6), /*gamma=*/6.0, /*cutoff_radius=*/1.0, /*time=*/1.0, steps,
                 /*initial_speed=*/1.3, segments);
  torch::manual_seed(seed);
  torch::NoGradGuard no_grad;
  net->weights.copy_(0.4 * torch::randn({36 * segments, 2}, kDouble));
  return net;
}

torch::Tensor RandomPoints(int n, std::uint64_t seed) {
  torch::manual_seed(seed);
  return torch::rand({n, 2}, kDouble) * 1.6 - 0.8;
}

TEST(RbfFlowNet, JacobianMatchesAutograd) {
  for (const int segments : {1, 3}) {  // 3 segments over 8 steps: uneven, floor(k S / K)
    RbfFlowNet net = RandomNet(1, 8, segments);
    const torch::Tensor x = RandomPoints(6, 2).requires_grad_(true);
    auto [z, j] = net->Forward(x);
    // Rows of d z / d x by autograd: samples are independent, so grad of sum_b z[b, i] is row i.
    for (int i = 0; i < 2; ++i) {
      const torch::Tensor row =
          torch::autograd::grad({z.select(1, i).sum()}, {x}, {}, /*retain_graph=*/true)[0];
      EXPECT_LT((row - j.select(1, i)).abs().max().item<double>(), 1e-12)
          << "row " << i << ", segments " << segments;
    }
    EXPECT_GT((j - torch::eye(2, kDouble)).abs().max().item<double>(), 0.1);  // not trivial
  }
}

TEST(RbfFlowNet, JacobianMatchesCentralDifferences) {
  RbfFlowNet net = RandomNet(3);
  torch::NoGradGuard no_grad;
  const torch::Tensor x = RandomPoints(6, 4);
  const torch::Tensor j = net->Forward(x).second;
  const double h = 1e-6;
  for (int c = 0; c < 2; ++c) {
    torch::Tensor xp = x.clone(), xm = x.clone();
    xp.select(1, c).add_(h);
    xm.select(1, c).sub_(h);
    const torch::Tensor fd = (net->Map(xp) - net->Map(xm)) / (2 * h);
    EXPECT_LT((fd - j.select(2, c)).abs().max().item<double>(), 1e-8) << "column " << c;
  }
  // Map is Forward's z.
  EXPECT_TRUE(torch::equal(net->Map(x), net->Forward(x).first));
}

TEST(RbfFlowNet, LossGradientMatchesFiniteDifferences) {
  RbfFlowNet net = RandomNet(5, /*steps=*/5);
  const torch::Tensor x = RandomPoints(8, 6);
  torch::manual_seed(7);
  const torch::Tensor target = torch::randn({8, 2}, kDouble);
  const torch::Tensor goal = torch::tensor({0.1, -0.2}, kDouble);
  const auto loss = [&] { return VelocityLoss(net->Velocity(x, goal), target); };
  net->zero_grad();
  loss().backward();
  const torch::Tensor grad_w = net->weights.grad().clone();
  const double grad_speed = net->log_speed.grad().item<double>();
  EXPECT_GT(grad_w.abs().max().item<double>(), 1e-3);

  torch::NoGradGuard no_grad;
  const double h = 1e-6;
  const auto central = [&](torch::Tensor p) {
    const double v = p.item<double>();
    p.fill_(v + h);
    const double up = loss().item<double>();
    p.fill_(v - h);
    const double down = loss().item<double>();
    p.fill_(v);
    return (up - down) / (2 * h);
  };
  // Every weight near the data (the others have zero gradient) and the speed.
  int checked = 0;
  for (int t = 0; t < 36; ++t)
    for (int c = 0; c < 2; ++c) {
      const double g = grad_w[t][c].item<double>();
      const double fd = central(net->weights[t][c]);
      EXPECT_NEAR(g, fd, 1e-6 * std::max(1.0, std::abs(fd))) << "W[" << t << "][" << c << "]";
      checked += std::abs(fd) > 1e-4;
    }
  EXPECT_GT(checked, 20);
  EXPECT_NEAR(grad_speed, central(net->log_speed), 1e-6);
}

/// The inducing states of a grid as RbfFlowNet's centres [m, D] (RbfGrid order).
template <int D>
torch::Tensor CentresOf(const RbfGrid<D>& grid) {
  torch::Tensor centres = torch::empty({grid.size(), D}, kDouble);
  for (int t = 0; t < grid.size(); ++t)
    for (int a = 0; a < D; ++a) centres[t][a] = grid.Centre(t)[a];
  return centres;
}

/// The grid RandomNet's centres come from (6 x 6 over [-1, 1]^2), as an RbfGridSpec.
RbfGridSpec<2> RandomNetGrid() {
  RbfGridSpec<2> g;
  g.lower = Vec<2>(-1, -1);
  g.counts = {6, 6};
  g.spacing = 0.4;
  g.gamma = 6.0;
  g.cutoff_radius = 1.0;
  return g;
}

/// Loss and gradients (W, log_speed) of ImitationTask's batch loss on `net` (autograd, or the net's
/// objective when it has one).
struct LossAndGradient {
  double loss = 0;
  torch::Tensor grad_w;
  double grad_speed = 0;
};
LossAndGradient TaskLoss(const std::shared_ptr<RbfFlowNetImpl>& net, const torch::Tensor& x,
                         const torch::Tensor& v, const torch::Tensor& goal,
                         const torch::Tensor& penalty_points, double penalty_weight) {
  ImitationTask task(net, x, v, x, v, goal, penalty_points, penalty_weight);
  net->zero_grad();
  const torch::Tensor loss = task.BatchLoss(torch::arange(x.size(0), torch::kInt64));
  loss.backward();
  return {loss.item<double>(), net->weights.grad().clone(), net->log_speed.grad().item<double>()};
}

// The hand-written objective (flow_objective.h) against autograd through RbfFlowNet: the same
// loss and gradients, with and without the invertibility penalty (active on some steps), with
// segments, in 2-D and 3-D.
TEST(RbfFlowNet, ObjectiveMatchesAutograd) {
  for (const int segments : {1, 3})
    for (const double weight_scale : {1.0, 6.0}) {  // 6: the penalty is active
      const auto make = [&] {
        RbfFlowNet net = RandomNet(11, 8, segments);
        torch::NoGradGuard no_grad;
        net->weights.mul_(weight_scale);
        return net.ptr();
      };
      const auto autograd = make(), fused = make();
      fused->SetObjective(MakeFlowObjective<2>(RandomNetGrid(), 1.0, 8, segments,
                                               RbfFlowNetImpl::kStepLipschitz, kGoalEpsilon));
      const torch::Tensor x = RandomPoints(13, 12), penalty = RandomPoints(5, 14);
      torch::manual_seed(15);
      const torch::Tensor v = torch::randn({13, 2}, kDouble);
      const torch::Tensor goal = torch::tensor({0.1, -0.2}, kDouble);
      for (const double pw : {0.0, 10.0}) {
        const LossAndGradient a = TaskLoss(autograd, x, v, goal, penalty, pw);
        const LossAndGradient f = TaskLoss(fused, x, v, goal, penalty, pw);
        const std::string what = "segments " + std::to_string(segments) + ", weights x" +
                                 std::to_string(weight_scale) + ", penalty " + std::to_string(pw);
        EXPECT_NEAR(f.loss, a.loss, 1e-11 * std::max(1.0, a.loss)) << what;
        const double scale = std::max(1.0, a.grad_w.abs().max().item<double>());
        EXPECT_LT((f.grad_w - a.grad_w).abs().max().item<double>(), 1e-10 * scale) << what;
        EXPECT_NEAR(f.grad_speed, a.grad_speed, 1e-10 * std::max(1.0, std::abs(a.grad_speed)))
            << what;
        EXPECT_GT(a.grad_w.abs().max().item<double>(), 1e-3) << what;
      }
      if (weight_scale > 1) {  // the penalty term must have been exercised
        torch::NoGradGuard no_grad;
        EXPECT_GT(autograd->InvertibilityPenalty(torch::cat({x, penalty})).item<double>(), 1e-4);
      }
    }
}

TEST(RbfFlowNet, ObjectiveMatchesAutogradIn3d) {
  RbfGridSpec<3> grid;
  grid.lower = Vec<3>(-1, -1, -1);
  grid.counts = {4, 4, 4};
  grid.spacing = 2.0 / 3;
  grid.gamma = 3.0;
  grid.cutoff_radius = 1.5;
  const torch::Tensor centres = CentresOf(RbfGrid<3>(grid));
  const auto make = [&] {
    auto net =
        std::make_shared<RbfFlowNetImpl>(centres, grid.gamma, grid.cutoff_radius, 0.8, 6, 0.9, 2);
    torch::manual_seed(21);
    torch::NoGradGuard no_grad;
    net->weights.copy_(1.5 * torch::randn({128, 3}, kDouble));
    return net;
  };
  const auto autograd = make(), fused = make();
  fused->SetObjective(
      MakeFlowObjective<3>(grid, 0.8, 6, 2, RbfFlowNetImpl::kStepLipschitz, kGoalEpsilon));
  torch::manual_seed(22);
  const torch::Tensor x = torch::rand({9, 3}, kDouble) * 1.4 - 0.7;
  const torch::Tensor v = torch::randn({9, 3}, kDouble);
  const torch::Tensor penalty = torch::rand({4, 3}, kDouble) - 0.5;
  const torch::Tensor goal = torch::tensor({0.05, 0.1, -0.1}, kDouble);
  const LossAndGradient a = TaskLoss(autograd, x, v, goal, penalty, 10.0);
  const LossAndGradient f = TaskLoss(fused, x, v, goal, penalty, 10.0);
  EXPECT_NEAR(f.loss, a.loss, 1e-11 * std::max(1.0, a.loss));
  const double scale = std::max(1.0, a.grad_w.abs().max().item<double>());
  EXPECT_LT((f.grad_w - a.grad_w).abs().max().item<double>(), 1e-10 * scale);
  EXPECT_NEAR(f.grad_speed, a.grad_speed, 1e-10 * std::max(1.0, std::abs(a.grad_speed)));
  torch::NoGradGuard no_grad;
  EXPECT_GT(autograd->InvertibilityPenalty(torch::cat({x, penalty})).item<double>(), 1e-4);
}

// Chunks are summed in a fixed order: any number of threads gives the same bits; the validation
// loss (no gradient) equals the batch loss without the penalty.
TEST(RbfFlowNet, ObjectiveIsThreadCountIndependent) {
  const auto objective = MakeFlowObjective<2>(RandomNetGrid(), 1.0, 8, 1,
                                              RbfFlowNetImpl::kStepLipschitz, kGoalEpsilon);
  RbfFlowNet net = RandomNet(31, 8, 1);
  const torch::Tensor w = net->weights.detach().mul(4).contiguous();
  const torch::Tensor x = RandomPoints(45, 32), penalty = RandomPoints(20, 33);
  torch::manual_seed(34);
  const torch::Tensor v = torch::randn({45, 2}, kDouble);
  const std::vector<double> goal = {0.2, 0.1};
  FlowObjectiveBatch b;
  b.x = x.data_ptr<double>();
  b.v = v.data_ptr<double>();
  b.batch = 45;
  b.goal = goal.data();
  b.penalty = penalty.data_ptr<double>();
  b.penalty_count = 20;
  b.penalty_weight = 10;
  std::vector<double> g1(72), g3(72);
  double s1 = 0, s3 = 0;
  const double l1 = objective->Evaluate(w.data_ptr<double>(), 0.3, b, 1, g1.data(), &s1);
  const double l3 = objective->Evaluate(w.data_ptr<double>(), 0.3, b, 3, g3.data(), &s3);
  EXPECT_EQ(l1, l3);
  EXPECT_EQ(s1, s3);
  EXPECT_EQ(g1, g3);
  EXPECT_EQ(objective->Evaluate(w.data_ptr<double>(), 0.3, b, 2, nullptr, nullptr), l1);
  b.penalty_weight = 0;
  const double plain = objective->Evaluate(w.data_ptr<double>(), 0.3, b, 2, nullptr, nullptr);
  EXPECT_LT(plain, l1);  // the penalty is active at these weights
  b.penalty_weight = -1;
  ExpectErrorContains(
      [&] { objective->Evaluate(w.data_ptr<double>(), 0.3, b, 1, nullptr, nullptr); },
      {"penalty weight", "-1"});
  // An objective for another grid is refused by the net.
  RbfGridSpec<2> other = RandomNetGrid();
  other.counts = {5, 6};
  ExpectErrorContains(
      [&] { net->SetObjective(MakeFlowObjective<2>(other, 1.0, 8, 1, 0.7, kGoalEpsilon)); },
      {"30 centres", "36"});
  ExpectErrorContains(  // the same count, another grid / another step count
      [&] {
        RbfGridSpec<2> shifted = RandomNetGrid();
        shifted.lower = Vec<2>(-0.9, -1);
        net->SetObjective(MakeFlowObjective<2>(shifted, 1.0, 8, 1, 0.7, kGoalEpsilon));
      },
      {"inducing state 0"});
  ExpectErrorContains(
      [&] {
        net->SetObjective(MakeFlowObjective<2>(RandomNetGrid(), 1.0, 4, 1, 0.7, kGoalEpsilon));
      },
      {"steps 4"});
}

TEST(RbfFlowNet, VelocityAtTheGoalIsZeroWithFiniteGradients) {
  RbfFlowNet net = RandomNet(8);
  const torch::Tensor goal = torch::tensor({0.25, -0.3}, kDouble);
  const torch::Tensor x = torch::stack({goal, torch::tensor({-0.5, 0.5}, kDouble)});
  const torch::Tensor v = net->Velocity(x, goal);
  EXPECT_LE(v[0].abs().max().item<double>(), 1e-6);  // kGoalEpsilon: rounding-level z - z_e
  EXPECT_GT(v[1].norm().item<double>(), 0.1);
  net->zero_grad();
  VelocityLoss(v, torch::ones({2, 2}, kDouble)).backward();
  EXPECT_TRUE(torch::isfinite(net->weights.grad()).all().item<bool>());
  EXPECT_TRUE(std::isfinite(net->log_speed.grad().item<double>()));
  EXPECT_GT(net->weights.grad().abs().max().item<double>(), 0);
}

TEST(RbfFlowNet, VelocityIsTheNaturalGradient) {
  // J f = -speed (z - z_e)/||z - z_e||: the image of the system is the unit-speed attractor.
  RbfFlowNet net = RandomNet(9);
  torch::NoGradGuard no_grad;
  const torch::Tensor x = RandomPoints(5, 10);
  const torch::Tensor goal = torch::tensor({0.0, 0.1}, kDouble);
  const torch::Tensor v = net->Velocity(x, goal);
  auto [z, j] = net->Forward(x);
  const torch::Tensor diff = z - net->Map(goal.unsqueeze(0));
  const torch::Tensor expected = -net->speed() * diff / diff.norm(2, 1, true);
  EXPECT_LT((torch::matmul(j, v.unsqueeze(2)).squeeze(2) - expected).abs().max().item<double>(),
            1e-12);
}

/// A quarter circle of radius 1 ending at the origin at unit speed:
///   p(theta) = (sin theta, 1 - cos theta),  theta from pi/2 down to 0,  p_dot = -(cos, sin).
void Arc(int n, double offset, torch::Tensor* positions, torch::Tensor* velocities) {
  *positions = torch::empty({n, 2}, kDouble);
  *velocities = torch::empty({n, 2}, kDouble);
  for (int i = 0; i < n; ++i) {
    const double theta = (M_PI / 2) * (i + offset) / n;
    (*positions)[i][0] = std::sin(theta);
    (*positions)[i][1] = 1 - std::cos(theta);
    (*velocities)[i][0] = -std::cos(theta);
    (*velocities)[i][1] = -std::sin(theta);
  }
}

TEST(RbfFlowNet, TrainingOnAnArcLowersTheValidationLoss) {
  torch::Tensor p, v, pv, vv;
  Arc(40, 0.25, &p, &v);
  Arc(15, 0.6, &pv, &vv);
  // 8 x 8 grid over [-0.4, 1.4]^2, spacing 0.257: gamma = 1 / (2 spacing^2), cut-off 3 spacings.
  const double spacing = 1.8 / 7;
  for (const bool objective : {false, true}) {
    auto net = std::make_shared<RbfFlowNetImpl>(
        GridCentres(-0.4, 1.4, 8), 1 / (2 * spacing * spacing), 3 * spacing, 1.0, 10, 1.0);
    if (objective) {  // the hand-written loss and gradient (flow_objective.h) train it as well
      RbfGridSpec<2> grid;
      grid.lower = Vec<2>(-0.4, -0.4);
      grid.counts = {8, 8};
      grid.spacing = spacing;
      grid.gamma = 1 / (2 * spacing * spacing);
      grid.cutoff_radius = 3 * spacing;
      net->SetObjective(
          MakeFlowObjective<2>(grid, 1.0, 10, 1, RbfFlowNetImpl::kStepLipschitz, kGoalEpsilon));
    }
    ImitationTask task(net, p, v, pv, vv, torch::zeros({2}, kDouble));
    EXPECT_EQ(task.num_train(), 40);
    const double before = task.ValidationLoss();
    torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(0.05));
    const torch::Tensor all = torch::arange(40, torch::kInt64);
    for (int it = 0; it < 60; ++it) {
      adam.zero_grad();
      task.BatchLoss(all).backward();
      adam.step();
    }
    const double after = task.ValidationLoss();
    EXPECT_GT(before, 0.05);
    EXPECT_LT(after, before / 20) << "before " << before << ", after " << after << ", objective "
                                  << objective;
  }
}

TEST(RbfFlowNet, BadArgumentsAreErrors) {
  const torch::Tensor c = GridCentres(0, 1, 3);
  ExpectErrorContains([&] { RbfFlowNet(c, -1, 0.5, 1, 4, 1); }, {"gamma", "-1"});
  ExpectErrorContains([&] { RbfFlowNet(c, 1, 0.5, 1, 0, 1); }, {"steps", "0"});
  ExpectErrorContains([&] { RbfFlowNet(c, 1, 0.5, 1, 4, 0); }, {"initial_speed"});
  ExpectErrorContains([&] { RbfFlowNet(c, 1, 0.5, 1, 4, 1, 5); }, {"segments", "steps = 4", "5"});
  ExpectErrorContains([&] { RbfFlowNet(c, 1, 0.5, 1, 4, 1, 2)->Field(c, 2); }, {"segment 2"});
  ExpectErrorContains([&] { RbfFlowNet(torch::zeros({3}, kDouble), 1, 0.5, 1, 4, 1); },
                      {"centres"});
  RbfFlowNet net(c, 1, 0.5, 1, 4, 1);
  ExpectErrorContains([&] { net->Forward(torch::zeros({2, 3}, kDouble)); }, {"x", "[B, 2]"});
  ExpectErrorContains([&] { net->Forward(torch::zeros({2, 2})); }, {"kFloat64"});
  ExpectErrorContains(
      [&] {
        VelocityLoss(torch::zeros({2, 2}), torch::zeros({3, 2}));
      },
      {"VelocityLoss"});
  const torch::Tensor p = torch::zeros({4, 2}, kDouble);
  ExpectErrorContains(
      [&] {
        ImitationTask(std::make_shared<RbfFlowNetImpl>(c, 1, 0.5, 1, 4, 1), p,
                      torch::zeros({3, 2}, kDouble), p, p, torch::zeros({2}, kDouble));
      },
      {"4 positions", "3 velocities"});
  torch::Tensor bad = p.clone();
  bad[1][1] = std::nan("");
  ExpectErrorContains(
      [&] {
        ImitationTask(std::make_shared<RbfFlowNetImpl>(c, 1, 0.5, 1, 4, 1), p, p, bad, p,
                      torch::zeros({2}, kDouble));
      },
      {"validation positions", "non-finite"});
}

#ifdef FORESIGHT_HAVE_RBF_FLOW_ENGINE
void CheckEngineParity(int segments) {
  RbfGridSpec<2> spec;
  spec.lower = Vec<2>(-1.0, -0.8);
  spec.counts = {9, 7};
  spec.spacing = 0.25;
  spec.gamma = 8;
  spec.cutoff_radius = 0.6;
  const RbfGrid<2> grid(spec);
  RbfFlowNet net(CentresOf(grid), spec.gamma, spec.cutoff_radius, 0.8, 7, 1.4, segments);
  torch::manual_seed(11);
  {
    torch::NoGradGuard no_grad;
    net->weights.copy_(0.3 * torch::randn({segments * grid.size(), 2}, kDouble));
  }
  const Vec<2> goal(0.13, 0.21);  // off the lattice: no centre at exactly the cut-off radius
  const ImitationSystem<2> system(
      RbfFlow<2>(grid, net->WeightsAsEigen(), FlowSettings<2>{0.8, 7, segments}), goal,
      net->speed());
  FlowWorkspace<2> ws = system.flow().MakeWorkspace();

  torch::NoGradGuard no_grad;
  const torch::Tensor x = RandomPoints(30, 12) * 1.2;
  auto [z, j] = net->Forward(x);
  const torch::Tensor v = net->Velocity(x, torch::tensor({goal[0], goal[1]}, kDouble));
  const torch::Tensor ze = net->Map(torch::tensor({{goal[0], goal[1]}}, kDouble));
  EXPECT_NEAR(system.goal_image()[0], ze[0][0].item<double>(), 1e-12);
  EXPECT_NEAR(system.goal_image()[1], ze[0][1].item<double>(), 1e-12);
  for (int b = 0; b < 30; ++b) {
    const Vec<2> xb(x[b][0].item<double>(), x[b][1].item<double>());
    Mat<2> jb;
    const Vec<2> zb = system.flow().Forward(xb, &ws, &jb);
    const Vec<2> vb = system.Velocity(xb, &ws);
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(zb[i], z[b][i].item<double>(), 1e-12);
      EXPECT_NEAR(vb[i], v[b][i].item<double>(), 1e-12 * std::max(1.0, std::abs(vb[i])));
      for (int k = 0; k < 2; ++k) EXPECT_NEAR(jb(i, k), j[b][i][k].item<double>(), 1e-12);
    }
  }
}

TEST(RbfFlowNet, EngineParity) { CheckEngineParity(1); }
// 3 segments over 7 steps (uneven): the net and the engine pick the same segment per step.
TEST(RbfFlowNet, EngineParityWithSegments) { CheckEngineParity(3); }
#endif

}  // namespace
}  // namespace foresight::imitation
