// The RBF flow's hand-written training objective (models/imitation/flow_objective.h),
// LibTorch-free: its gradient against central differences of its own loss to 1e-6 relative (weights
// of every segment and log_speed, with the invertibility penalty active), in 2-D and 3-D, and bad
// input refused. The comparison with LibTorch autograd through the integration is in
// flow_net_test.cc.
#include "models/imitation/flow_objective.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "inference/imitation/rbf_grid.h"
#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

using testing::ExpectErrorContains;

template <int D>
RbfGridSpec<D> Grid() {
  RbfGridSpec<D> g;
  g.lower = Vec<D>::Constant(-1);
  g.counts.fill(D == 2 ? 6 : 4);
  g.spacing = 2.0 / (g.counts[0] - 1);
  g.gamma = D == 2 ? 6.0 : 3.0;
  g.cutoff_radius = D == 2 ? 1.0 : 1.5;
  return g;
}

template <int D>
void CheckAgainstCentralDifferences(int segments, double expansion) {
  const RbfGridSpec<D> grid = Grid<D>();
  const int steps = 6;
  const auto objective = MakeFlowObjective<D>(grid, 0.9, steps, segments, 0.7, 1e-9);
  const int m = objective->num_centres();
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(-0.7, 0.7);
  // An expanding field (weights along the centres, so I + h DV stays well conditioned: J^-1 and
  // the velocities stay moderate) with a random part; `expansion` large enough activates the
  // invertibility penalty.
  const RbfGrid<D> g(grid);
  std::vector<double> w(static_cast<std::size_t>(segments * m * D));
  for (int k = 0; k < segments * m; ++k)
    for (int a = 0; a < D; ++a)
      w[static_cast<std::size_t>(k * D + a)] = expansion * g.Centre(k % m)[a] + 0.2 * normal(rng);
  const int b = 7, r = 5;
  std::vector<double> x(b * D), vel(b * D), pen(r * D), goal(D, 0.05);
  for (double& v : x) v = uniform(rng);
  for (double& v : vel) v = normal(rng);
  for (double& v : pen) v = uniform(rng);
  FlowObjectiveBatch batch;
  batch.x = x.data();
  batch.v = vel.data();
  batch.batch = b;
  batch.goal = goal.data();
  batch.penalty = pen.data();
  batch.penalty_count = r;
  batch.penalty_weight = 10;
  const double log_speed = 0.2;
  std::vector<double> grad(w.size());
  double grad_speed = 0;
  objective->Evaluate(w.data(), log_speed, batch, 2, grad.data(), &grad_speed);
  const auto loss = [&](double ls) {
    return objective->Evaluate(w.data(), ls, batch, 1, nullptr, nullptr);
  };
  const double h = 1e-6;
  int checked = 0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    const double keep = w[k];
    w[k] = keep + h;
    const double up = loss(log_speed);
    w[k] = keep - h;
    const double down = loss(log_speed);
    w[k] = keep;
    const double fd = (up - down) / (2 * h);
    EXPECT_NEAR(grad[k], fd, 1e-6 * std::max(1.0, std::abs(fd))) << "weight " << k;
    checked += std::abs(fd) > 1e-4;
  }
  EXPECT_GT(checked, static_cast<int>(w.size()) / 4);
  const double fd_speed = (loss(log_speed + h) - loss(log_speed - h)) / (2 * h);
  EXPECT_NEAR(grad_speed, fd_speed, 1e-6 * std::max(1.0, std::abs(fd_speed)));
  // The penalty is active at these weights: the loss with it exceeds the loss without.
  FlowObjectiveBatch plain = batch;
  plain.penalty_weight = 0;
  if (expansion >= 1) {
    EXPECT_GT(loss(log_speed),
              objective->Evaluate(w.data(), log_speed, plain, 1, nullptr, nullptr) + 1e-6);
  }
}

TEST(FlowObjective, GradientMatchesCentralDifferences2d) {
  CheckAgainstCentralDifferences<2>(1, 0.2);
  CheckAgainstCentralDifferences<2>(2, 3.0);
}

TEST(FlowObjective, GradientMatchesCentralDifferences3d) {
  CheckAgainstCentralDifferences<3>(2, 3.0);
}

TEST(FlowObjective, BadInputIsRefused) {
  ExpectErrorContains([] { MakeFlowObjective<2>(Grid<2>(), 1.0, 0, 1, 0.7, 1e-9); },
                      {"steps", "0"});
  ExpectErrorContains([] { MakeFlowObjective<2>(Grid<2>(), 1.0, 4, 5, 0.7, 1e-9); },
                      {"segments", "5"});
  ExpectErrorContains([] { MakeFlowObjective<2>(Grid<2>(), -1.0, 4, 1, 0.7, 1e-9); }, {"time"});
  const auto objective = MakeFlowObjective<2>(Grid<2>(), 1.0, 4, 1, 0.7, 1e-9);
  std::vector<double> w(72, 0.0), x = {0.1, 0.2}, v = {0.0, 1.0}, goal = {0.0, 0.0};
  FlowObjectiveBatch b;
  b.x = x.data();
  b.v = v.data();
  b.goal = goal.data();
  b.batch = 0;
  ExpectErrorContains([&] { objective->Evaluate(w.data(), 0, b, 1, nullptr, nullptr); },
                      {"batch", "0"});
  b.batch = 1;
  b.penalty_count = 3;  // without data
  ExpectErrorContains([&] { objective->Evaluate(w.data(), 0, b, 1, nullptr, nullptr); },
                      {"3 penalty points"});
  b.penalty_count = 0;
  double gs = 0;
  ExpectErrorContains([&] { objective->Evaluate(w.data(), 0, b, 1, nullptr, &gs); },
                      {"both gradients"});
}

}  // namespace
}  // namespace foresight::imitation
