// The manipulation kind's bench (`foresight bench CONFIG|RUN_DIR`): manipulation runtime figures
// measured in one run on one thread (except the GFCS solve, which uses the config's threads):
// forward kinematics of every collision sphere (positions; with Jacobians and J' q_d), one fabric
// step, a full rollout to the goal, and a GFCS solve (one batch, uniform sampler) with and without
// pruning (GfcsParams::prune: the same top candidates), and the step, rollout and solve again with
// the fabric's broad phase switched (the rollouts compared bit for bit). Medians of repeated runs
// over the config's problems. KDL side by side: the bench_kinematics benchmark (experiments/).

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

/// The fabric's work per step along rollouts (FabricProbe's counts), summed over their states.
struct StepWork {
  double steps = 0, world_queries = 0, pair_distances = 0, obstacle_terms = 0, self_terms = 0;

  /// Adds the states of one rollout from the problem's start (at rest) to its goal.
  void AddRollout(const Fabric& fabric, const ManipulationProblem& problem) {
    FabricWorkspace ws = fabric.MakeWorkspace();
    std::vector<JointVector> path{problem.start};
    fabric.Rollout(problem.start, JointVector::Zero(), problem.goal, &ws, &path);
    JointVector qdd;
    for (std::size_t k = 0; k + 1 < path.size(); ++k) {
      fabric.Acceleration(path[k], (path[k + 1] - path[k]) / fabric.params().dt, problem.goal, &ws,
                          &qdd);
      steps += 1;
      world_queries += ws.probe.obstacle_distances;
      pair_distances += ws.probe.pair_distances;
      obstacle_terms += ws.probe.active_obstacle_terms;
      self_terms += ws.probe.active_self_terms;
    }
  }
  double PerStep(double total) const { return total / std::max(1.0, steps); }
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

  // Fabric step, rollout and GFCS solve on each problem's world (valid start states); each also
  // with the broad phase switched (FabricParams::broad_phase; false computes every distance), the
  // rollouts compared bit for bit.
  FabricParams reference_params = c.fabric;
  reference_params.broad_phase = !c.fabric.broad_phase;
  std::vector<double> steps, rollouts, rollout_times, solves, unpruned_solves, pruned_shares;
  std::vector<double> reference_steps, reference_rollouts, reference_solves;
  bool same_rollouts = true;
  StepWork work;  // along every problem's rollout
  for (const ManipulationProblem& problem : problems) {
    const ValidityChecker checker(robot, problem.world);
    if (checker.Check(problem.start, &data) != Validity::kValid) continue;
    GfcsQuery query;
    query.start = problem.start;
    query.goal = problem.goal;
    UniformSampler sampler(limits.lower, limits.upper);
    GfcsParams params = c.gfcs;
    params.batches = 1;
    // One fabric's step, rollout and pruned solve, appended to the three lists.
    const auto measure = [&](const Fabric& fabric, std::vector<double>* step_times,
                             std::vector<double>* rollout_times_s, RolloutResult* r) {
      FabricWorkspace ws = fabric.MakeWorkspace();
      JointVector qdd;
      step_times->push_back(SecondsPerCall(a.repeats, calls, [&](int i) {
        fabric.Acceleration(problem.start, 0.1 * qds[static_cast<std::size_t>(i) % qds.size()],
                            problem.goal, &ws, &qdd);
      }));
      rollout_times_s->push_back(SecondsPerCall(a.repeats, 1, [&](int) {
        *r = fabric.Rollout(problem.start, JointVector::Zero(), problem.goal, &ws);
      }));
      SolveGfcop(fabric, query, &sampler, params);  // warm-up: no timed solve runs cold
    };
    const Fabric fabric(robot, problem.world, c.fabric);
    RolloutResult r;
    measure(fabric, &steps, &rollouts, &r);
    rollout_times.push_back(r.t);
    params.prune = false;
    unpruned_solves.push_back(
        SecondsPerCall(a.repeats, 1, [&](int) { SolveGfcop(fabric, query, &sampler, params); }));
    params.prune = true;
    GfcsSolution solution;
    solves.push_back(SecondsPerCall(
        a.repeats, 1, [&](int) { solution = SolveGfcop(fabric, query, &sampler, params); }));
    pruned_shares.push_back(static_cast<double>(solution.pruned) /
                            std::max(1, solution.evaluations));

    const Fabric reference(robot, problem.world, reference_params);
    RolloutResult reference_r;
    measure(reference, &reference_steps, &reference_rollouts, &reference_r);
    work.AddRollout(fabric, problem);
    same_rollouts = same_rollouts && reference_r.status == r.status && reference_r.q == r.q &&
                    reference_r.qd == r.qd && reference_r.steps == r.steps;
    reference_solves.push_back(
        SecondsPerCall(a.repeats, 1, [&](int) { SolveGfcop(reference, query, &sampler, params); }));
  }
  FS_THROW_UNLESS(!steps.empty(), "bench: no problem has a valid start");
  const double step = Median(steps), rollout = Median(rollouts), solve = Median(solves);
  const double unpruned = Median(unpruned_solves), pruned_share = Median(pruned_shares);
  const double integrated = Median(rollout_times);
  const double reference_step = Median(reference_steps);
  const double reference_rollout = Median(reference_rollouts);
  const double reference_solve = Median(reference_solves);
  const auto per_step = [&](double total) { return work.PerStep(total); };
  const char* reference_name = reference_params.broad_phase ? "broad_phase" : "full";

  if (req.json) {
    std::cout << std::setprecision(6) << "{\"spheres\": " << robot.num_spheres()
              << ", \"fk_us\": " << fk * 1e6 << ", \"fk_jacobians_us\": " << fk_jac * 1e6
              << ", \"fabric_step_us\": " << step * 1e6 << ", \"rollout_ms\": " << rollout * 1e3
              << ", \"rollout_integrated_s\": " << integrated << ", \"gfcs_solve_s\": " << solve
              << ", \"gfcs_solve_unpruned_s\": " << unpruned
              << ", \"gfcs_pruned_share\": " << pruned_share
              << ", \"gfcs_batch_size\": " << c.gfcs.batch_size
              << ", \"problems\": " << steps.size()
              << ", \"broad_phase\": " << (c.fabric.broad_phase ? "true" : "false")
              << ", \"fabric_step_" << reference_name << "_us\": " << reference_step * 1e6
              << ", \"rollout_" << reference_name << "_ms\": " << reference_rollout * 1e3
              << ", \"gfcs_solve_" << reference_name << "_s\": " << reference_solve
              << ", \"same_rollouts\": " << (same_rollouts ? "true" : "false")
              << ", \"per_step\": {\"world_queries\": " << per_step(work.world_queries)
              << ", \"pair_distances\": " << per_step(work.pair_distances)
              << ", \"active_obstacle_terms\": " << per_step(work.obstacle_terms)
              << ", \"active_self_terms\": " << per_step(work.self_terms)
              << ", \"checked_pairs\": " << robot.self_collision_pairs().size() << "}}\n";
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
            << unpruned / solve << "x the pruned time)\n"
            << "broad phase " << (c.fabric.broad_phase ? "on" : "off") << " (the config) vs "
            << (reference_params.broad_phase ? "on" : "off") << ": step " << step * 1e6 << " vs "
            << reference_step * 1e6 << " us, rollout " << rollout * 1e3 << " vs "
            << reference_rollout * 1e3 << " ms, solve " << std::setprecision(3) << solve << " vs "
            << reference_solve << std::setprecision(2) << " s; rollouts "
            << (same_rollouts ? "identical" : "DIFFERENT") << "\n"
            << "per step along the rollouts: " << per_step(work.world_queries)
            << " world distance queries, " << per_step(work.pair_distances) << " of "
            << robot.self_collision_pairs().size() << " pair distances, "
            << per_step(work.obstacle_terms) << " obstacle and " << per_step(work.self_terms)
            << " self-collision terms active\n";
}
}  // namespace

void SetBenchStep(ExperimentKind* kind) {
  SetBench<ManipulationBenchOptions>(kind, RunManipulationBench);
}

}  // namespace foresight::manipulation
