// One training step's loss and gradient of the diffeomorphic-template flow (thesis ch 8) at the
// LASA configuration (19 x 19 inducing states, gamma 100, cut-off 0.425, 10 Euler steps, a batch
// of 128 plus the 144-point penalty lattice): LibTorch autograd through the integration against
// the hand-written sparse objective (models/imitation/flow_objective.h), side by side in one run,
// medians of repeated runs, at 1 and 2 threads. Prints the figures and the ratio.
//   build/bin/bench_flow_objective [--repeats N]
#include <torch/torch.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/bench.h"
#include "inference/imitation/rbf_grid.h"
#include "models/imitation/flow_net.h"
#include "training/diffeo/imitation_task.h"

using namespace foresight;
using namespace foresight::imitation;

namespace {

struct Setup {
  RbfGridSpec<2> grid;
  torch::Tensor centres, weights, x, v, penalty, goal;
};

Setup MakeSetup() {
  Setup s;
  s.grid = RbfGrid<2>::Covering(Vec<2>(-0.5, -0.5), Vec<2>(0.5, 0.5), 0.15, 0.07, 100, 0.425);
  const RbfGrid<2> g(s.grid);
  s.centres = torch::empty({g.size(), 2}, kDouble);
  for (int t = 0; t < g.size(); ++t)
    for (int a = 0; a < 2; ++a) s.centres[t][a] = g.Centre(t)[a];
  torch::manual_seed(1);
  // Weights of a trained-looking field: smooth, |V| ~ 1, some steps near the penalty's bound.
  s.weights = 0.05 * torch::randn({g.size(), 2}, kDouble);
  s.x = torch::rand({128, 2}, kDouble) - 0.5;
  s.v = torch::randn({128, 2}, kDouble);
  s.penalty = torch::rand({144, 2}, kDouble) * 1.3 - 0.65;
  s.goal = torch::zeros({2}, kDouble);
  return s;
}

/// Median seconds of one loss + backward on `net` over `repeats` runs.
double StepSeconds(const std::shared_ptr<RbfFlowNetImpl>& net, const Setup& s, int repeats) {
  ImitationTask task(net, s.x, s.v, s.x, s.v, s.goal, s.penalty, 10.0);
  const torch::Tensor all = torch::arange(128, torch::kInt64);
  for (int i = 0; i < 3; ++i) task.BatchLoss(all).backward();  // warm-up
  return bench::MedianSeconds(repeats, [&] {
    net->zero_grad();
    task.BatchLoss(all).backward();
  });
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 30;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--repeats") == 0) repeats = std::max(1, std::atoi(argv[i + 1]));
  const Setup s = MakeSetup();
  const auto make = [&](bool objective) {
    auto net = std::make_shared<RbfFlowNetImpl>(s.centres, 100, 0.425, 1.0, 10, 1.0);
    torch::NoGradGuard no_grad;
    net->weights.copy_(s.weights);
    if (objective)
      net->SetObjective(
          MakeFlowObjective<2>(s.grid, 1.0, 10, 1, RbfFlowNetImpl::kStepLipschitz, kGoalEpsilon));
    return net;
  };
  std::printf(
      "flow training step (loss + gradient), %d inducing states, 10 Euler steps, batch 128 "
      "+ 144 penalty points, median of %d runs:\n",
      static_cast<int>(s.centres.size(0)), repeats);
  for (const int threads : {1, 2}) {
    torch::set_num_threads(threads);
    const double autograd = StepSeconds(make(false), s, repeats);
    const double objective = StepSeconds(make(true), s, repeats);
    std::printf("  %d thread(s): autograd %.2f ms, hand-written objective %.2f ms (%.1fx)\n",
                threads, 1e3 * autograd, 1e3 * objective, autograd / objective);
  }
  return 0;
}
