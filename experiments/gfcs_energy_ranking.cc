// Does the GFCS energy model rank command sequences by whether they reach the goal? (thesis ch 9,
// "Learning to Sample for Optimisation": positives should have low energy.)
//
// For every problem: N candidates drawn uniformly in the joint limits, each rolled out by the
// fabric (reached the goal or not) and scored by the energy model in the problem's context. Per
// family it prints
//   - the share of uniform candidates that reach the goal;
//   - the ranking AUC of -E: the probability that a reaching candidate has a lower energy than a
//     failing one of the same problem (0.5 = no information; averaged over the problems with both);
//   - the same AUC for the nearest-neighbour baseline's score, minus the distance (normalised
//     commands) to the closest of the 20 solutions the nearest sampler would return;
//   - problems solved by a batch of the first 20 uniform candidates, and by the 20 lowest-energy
//     ones of all N (selection by the energy without SGLD).
//   gfcs_energy_ranking --model runs/gfcs_all/model.h5 --data ../shared/data --first 51 --last 75
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

#include "core/binary_metrics.h"
#include "core/error.h"
#include "inference/manipulation/energy_model.h"
#include "inference/manipulation/fabric.h"
#include "inference/manipulation/gfcs.h"
#include "inference/manipulation/mbm_problem.h"
#include "inference/manipulation/nearest_sampler.h"

namespace fm = foresight::manipulation;

namespace {

/// P(score of a positive > score of a negative) with ties counted half (core's ROC AUC); -1
/// without both classes.
double RankingAuc(const std::vector<double>& score, const std::vector<std::uint8_t>& label) {
  const bool both = std::count(label.begin(), label.end(), 1) > 0 &&
                    std::count(label.begin(), label.end(), 0) > 0;
  return both ? foresight::EvaluateBinary(score, label).auc : -1.0;
}

/// Whether each column of `y` reaches the goal, rolled out on `threads` threads. An error in a
/// thread is rethrown here.
std::vector<std::uint8_t> Reached(const fm::Fabric& fabric, const fm::GfcsQuery& query,
                                  const Eigen::MatrixXd& y, int threads) {
  std::vector<std::uint8_t> reached(static_cast<std::size_t>(y.cols()), 0);
  std::vector<std::string> errors(static_cast<std::size_t>(threads));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      try {
        fm::FabricWorkspace ws = fabric.MakeWorkspace();
        for (Eigen::Index c = t; c < y.cols(); c += threads)
          reached[static_cast<std::size_t>(c)] =
              fm::EvaluateCommandSequence(fabric, query, y.col(c), 100.0, &ws).reached;
      } catch (const std::exception& e) {
        errors[static_cast<std::size_t>(t)] = e.what();
      }
    });
  for (std::thread& th : pool) th.join();
  for (const std::string& e : errors) FS_THROW_UNLESS(e.empty(), "rollouts: ", e);
  return reached;
}

struct FamilyStats {
  int problems = 0, candidates = 0, reaching = 0;
  double auc_energy = 0, auc_nearest = 0;
  int auc_problems = 0;
  int solved_uniform = 0, solved_lowest_energy = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"GFCS energy model: does it rank reaching command sequences first?"};
  std::string model_path, data_root;
  std::vector<std::string> families = {"table_under_pick_panda", "box_panda",
                                       "bookshelf_tall_panda",   "cage_panda",
                                       "bookshelf_thin_panda",   "bookshelf_small_panda"};
  int first = 41, last = 50, candidates = 200, batch = 20, threads = 2;
  app.add_option("--model", model_path, "gfcs_energy artifact (model.h5)")->required();
  app.add_option("--data", data_root, "data root holding motionbenchmaker_panda, franka_panda")
      ->required();
  app.add_option("--families", families, "MotionBenchMaker families");
  app.add_option("--first", first, "first problem");
  app.add_option("--last", last, "last problem");
  app.add_option("--candidates", candidates, "uniform candidates per problem (N)")
      ->check(CLI::Range(20, 100000));
  app.add_option("--batch", batch, "batch size of the selections")->check(CLI::Range(1, 100000));
  app.add_option("--threads", threads, "rollout threads")->check(CLI::Range(1, 256));
  CLI11_PARSE(app, argc, argv);
  if (batch > candidates) {
    std::cerr << "--batch " << batch << " exceeds --candidates " << candidates << "\n";
    return 2;
  }
  try {
    const fm::EnergyModel model = fm::EnergyModel::Load(model_path);
    FS_THROW_UNLESS(model.intermediate_commands() == 1, model_path, ": ",
                    model.intermediate_commands(), " intermediate commands; this tool takes 1");
    const fm::RobotModel robot = fm::RobotModel::LoadPanda(data_root + "/franka_panda");
    const bool memory = !model.parts().memory.empty();
    fm::EnergyModel::Workspace ews = model.MakeWorkspace(candidates);
    fm::UniformSampler uniform(robot.limits().lower, robot.limits().upper);
    std::printf(
        "| family | problems | reaching share of uniform candidates | AUC of -E | AUC of "
        "nearest memory (-distance) | solved: first %d uniform | solved: %d lowest E of "
        "%d uniform |\n|---|---|---|---|---|---|---|\n",
        batch, batch, candidates);
    for (const std::string& family : families) {
      FamilyStats s;
      for (const fm::ManipulationProblem& p :
           fm::LoadMbmFamily(data_root + "/motionbenchmaker_panda/problems", family, first, last)) {
        const fm::Fabric fabric(robot, p.world, fm::FabricParams{});
        fm::GfcsQuery query;
        query.start = p.start;
        query.goal = p.goal;
        const Eigen::VectorXf encoding = model.EncodeWorld(p.world);
        Eigen::VectorXf context;
        model.Context(query, encoding, &context);
        std::mt19937_64 rng(static_cast<std::uint64_t>(p.index));
        Eigen::MatrixXd y;
        uniform.Sample(query, 1, candidates, &rng, &y);
        Eigen::MatrixXf u(fm::kDof, candidates);
        for (int c = 0; c < candidates; ++c) u.col(c) = model.RadiansToCommands(y.col(c));
        Eigen::VectorXf energy;
        model.EnergyAndGradient(context, u, &energy, nullptr, &ews);
        const std::vector<std::uint8_t> reached = Reached(fabric, query, y, threads);

        std::vector<double> minus_energy(reached.size()), minus_distance(reached.size(), 0.0);
        for (int c = 0; c < candidates; ++c) minus_energy[c] = -energy[c];
        if (memory) {
          fm::NearestSampler nearest(model, 4);
          nearest.SetEncoding(encoding);
          Eigen::MatrixXd recalled;
          nearest.Sample(query, 1, batch, &rng, &recalled);
          Eigen::MatrixXf recalled_u(fm::kDof, batch);
          for (int c = 0; c < batch; ++c)
            recalled_u.col(c) = model.RadiansToCommands(recalled.col(c));
          for (int c = 0; c < candidates; ++c)
            minus_distance[c] = -(recalled_u.colwise() - u.col(c)).colwise().norm().minCoeff();
        }
        const double auc = RankingAuc(minus_energy, reached);
        if (auc >= 0) {
          s.auc_energy += auc;
          s.auc_nearest += RankingAuc(minus_distance, reached);
          ++s.auc_problems;
        }
        std::vector<int> order(reached.size());
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(),
                         [&](int a, int b) { return energy[a] < energy[b]; });
        bool first_batch = false, lowest = false;
        for (int c = 0; c < batch; ++c) {
          first_batch |= reached[c] != 0;
          lowest |= reached[order[c]] != 0;
        }
        ++s.problems;
        s.candidates += candidates;
        s.reaching += std::accumulate(reached.begin(), reached.end(), 0);
        s.solved_uniform += first_batch;
        s.solved_lowest_energy += lowest;
      }
      const double n = std::max(1, s.auc_problems);
      char nearest_auc[32] = "-";
      if (memory) std::snprintf(nearest_auc, sizeof(nearest_auc), "%.3f", s.auc_nearest / n);
      std::printf("| %s | %d | %.3f | %.3f (%d problems) | %s | %d | %d |\n", family.c_str(),
                  s.problems, static_cast<double>(s.reaching) / std::max(1, s.candidates),
                  s.auc_energy / n, s.auc_problems, nearest_auc, s.solved_uniform,
                  s.solved_lowest_energy);
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    std::cerr << "gfcs_energy_ranking: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
