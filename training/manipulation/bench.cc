// The manipulation kind's bench (`foresight bench CONFIG|RUN_DIR`): manipulation runtime figures
// measured in one run on one thread (except the GFCS solve, which uses the config's threads):
// forward kinematics of every collision sphere (positions; with Jacobians and J' q_d), one fabric
// step, a full rollout to the goal, and a GFCS solve (one batch, uniform sampler) with and without
// pruning (GfcsParams::prune: the same top candidates). Medians of repeated runs over the config's
// problems. KDL side by side: the bench_kinematics benchmark (experiments/).

#include "core/bench.h"

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

#include "core/error.h"
#include "inference/manipulation/fabric.h"
#include "inference/manipulation/gfcs.h"
#include "inference/manipulation/validity.h"
#include "training/kinds.h"
#include "training/manipulation/plan.h"

namespace foresight::manipulation {
namespace {
using bench::Clock;
using bench::Median;
using bench::SecondsPerCall;
using namespace manipulation;  // NOLINT: a manipulation benchmark

struct ManipulationBenchOptions {
  int repeats = 7;

  template <class A>
  void Serialize(A* a) {
    a->Visit("repeats", &repeats, config::Range::Closed(1, 1000), "timed runs (median reported)");
  }
};

void RunManipulationBench(const BenchRequest& req, const ManipulationBenchOptions& a) {
  const auto c = LoadBenchConfig<ExperimentConfig>(req);
  const RobotModel robot = LoadExperimentRobot(c);
  const std::vector<ManipulationProblem> problems = LoadExperimentProblems(c, robot);
  FS_THROW_UNLESS(!problems.empty(), "bench: the config has no problems");

  // Random configurations within the limits, shared by ours and KDL.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  const JointLimits& limits = robot.limits();
  std::vector<JointVector> qs(256), qds(256);
  for (std::size_t i = 0; i < qs.size(); ++i)
    for (int j = 0; j < kDof; ++j) {
      qs[i][j] = limits.lower[j] + unit(rng) * (limits.upper[j] - limits.lower[j]);
      qds[i][j] = 2 * unit(rng) - 1;
    }
  const int calls = 2000;
  KinematicsData data = robot.MakeData();
  const double fk = SecondsPerCall(a.repeats, calls, [&](int i) {
    ForwardKinematics(robot, qs[static_cast<std::size_t>(i) % qs.size()], &data);
  });
  const double fk_jac = SecondsPerCall(a.repeats, calls, [&](int i) {
    const std::size_t k = static_cast<std::size_t>(i) % qs.size();
    ForwardKinematicsWithJacobians(robot, qs[k], qds[k], &data);
  });

  // Fabric step and rollout on each problem's world (valid start states).
  std::vector<double> steps, rollouts, rollout_times, solves, unpruned_solves, pruned_shares;
  for (const ManipulationProblem& problem : problems) {
    const ValidityChecker checker(robot, problem.world);
    if (checker.Check(problem.start, &data) != Validity::kValid) continue;
    const Fabric fabric(robot, problem.world, c.fabric);
    FabricWorkspace ws = fabric.MakeWorkspace();
    JointVector qdd;
    steps.push_back(SecondsPerCall(a.repeats, calls, [&](int i) {
      fabric.Acceleration(problem.start, 0.1 * qds[static_cast<std::size_t>(i) % qds.size()],
                          problem.goal, &ws, &qdd);
    }));
    RolloutResult r;
    rollouts.push_back(SecondsPerCall(a.repeats, 1, [&](int) {
      r = fabric.Rollout(problem.start, JointVector::Zero(), problem.goal, &ws);
    }));
    rollout_times.push_back(r.t);
    UniformSampler sampler(limits.lower, limits.upper);
    GfcsParams params = c.gfcs;
    params.batches = 1;
    GfcsQuery query;
    query.start = problem.start;
    query.goal = problem.goal;
    SolveGfcop(fabric, query, &sampler, params);  // warm-up: neither timed solve runs cold
    params.prune = false;
    unpruned_solves.push_back(
        SecondsPerCall(a.repeats, 1, [&](int) { SolveGfcop(fabric, query, &sampler, params); }));
    params.prune = true;
    GfcsSolution solution;
    solves.push_back(SecondsPerCall(
        a.repeats, 1, [&](int) { solution = SolveGfcop(fabric, query, &sampler, params); }));
    pruned_shares.push_back(static_cast<double>(solution.pruned) /
                            std::max(1, solution.evaluations));
  }
  FS_THROW_UNLESS(!steps.empty(), "bench: no problem has a valid start");
  const double step = Median(steps), rollout = Median(rollouts), solve = Median(solves);
  const double unpruned = Median(unpruned_solves), pruned_share = Median(pruned_shares);
  const double integrated = Median(rollout_times);

  if (req.json) {
    std::cout << std::setprecision(6) << "{\"spheres\": " << robot.num_spheres()
              << ", \"fk_us\": " << fk * 1e6 << ", \"fk_jacobians_us\": " << fk_jac * 1e6
              << ", \"fabric_step_us\": " << step * 1e6 << ", \"rollout_ms\": " << rollout * 1e3
              << ", \"rollout_integrated_s\": " << integrated << ", \"gfcs_solve_s\": " << solve
              << ", \"gfcs_solve_unpruned_s\": " << unpruned
              << ", \"gfcs_pruned_share\": " << pruned_share
              << ", \"gfcs_batch_size\": " << c.gfcs.batch_size
              << ", \"problems\": " << steps.size() << "}\n";
    return;
  }
  std::cout << std::fixed << std::setprecision(2) << "robot: " << robot.num_spheres()
            << " spheres; " << steps.size() << " problems; medians of " << a.repeats
            << " repeats, one thread unless stated\n"
            << "FK, sphere centres                " << std::setw(8) << fk * 1e6 << " us\n"
            << "FK + Jacobians + J' q_d           " << std::setw(8) << fk_jac * 1e6 << " us\n"
            << "fabric step                       " << std::setw(8) << step * 1e6 << " us\n"
            << "rollout to the goal               " << std::setw(8) << rollout * 1e3 << " ms   ("
            << integrated << " s integrated)\n"
            << "GFCS solve, 1 batch of " << c.gfcs.batch_size << "       " << std::setw(8) << solve
            << " s   (" << (c.gfcs.threads > 0 ? c.gfcs.threads : 0)
            << " threads, 0: all cores; pruned, median share of candidates stopped " << pruned_share
            << ")\n"
            << "  the same, unpruned              " << std::setw(8) << unpruned << " s   ("
            << unpruned / solve << "x the pruned time)\n";
}
}  // namespace

void SetBenchStep(ExperimentKind* kind) {
  SetBench<ManipulationBenchOptions>(kind, RunManipulationBench);
}

}  // namespace foresight::manipulation
