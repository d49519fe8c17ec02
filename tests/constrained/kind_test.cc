// The constrained-prediction run end to end on tiny synthetic scenes: a run interrupted in the
// first epoch resumes to completion, eval.json holds every block, and eval refuses overrides that
// would change what the run was trained and scored on.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/config.h"
#include "tests/test_util.h"
#include "training/constrained/pipeline.h"
#include "training/kinds.h"

namespace foresight {
namespace {
namespace fs = std::filesystem;
using testing::ExpectErrorContains;
using testing::TempDir;

constrained::ExperimentConfig TinyConfig() {
  return config::ExperimentConfigFromYaml<constrained::ExperimentConfig>(
      "model: constrained\ndata: {source: synthetic, max_maps: 4, synthetic_tracks: 12}\n"
      "split: {by_scene: true, val_fraction: 0.25, test_fraction: 0.25}\n"
      "windows: {observed: 6, predicted: 6, stride: 3}\nbasis: {num_centres: 4}\n"
      "network: {hidden: [16], components: 2, u_param: diagonal}\n"
      "train: {epochs: 2, batch_size: 32, progress: none}\nktm: {references: 8}\n"
      "naive: {hidden: [16]}\neval: {max_windows: 8, accuracy_windows: 2, accuracy_samples: 500, "
      "plot_windows: 1, plot_samples: 3}\n",
      "tiny");
}

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ConstrainedRun, InterruptedInTheFirstEpochResumesAndEvaluates) {
  const TempDir tmp;
  const std::string run = tmp.File("run");
  const constrained::ExperimentConfig c = TinyConfig();
  std::atomic<bool> stop{true};
  EXPECT_FALSE(constrained::TrainConstrainedRun(c, run, false, &stop));
  EXPECT_FALSE(fs::exists(run + "/prior.h5"));
  // A fresh start in the same directory is refused; --resume continues.
  ExpectErrorContains([&] { constrained::TrainConstrainedRun(c, run, false, nullptr); }, {run});
  stop = false;
  ASSERT_TRUE(constrained::TrainConstrainedRun(c, run, true, &stop));
  for (const char* a : {"/prior.h5", "/ktm.h5", "/naive.h5"}) EXPECT_TRUE(fs::exists(run + a)) << a;
  EXPECT_TRUE(fs::exists(run + "/maps"));

  const std::string json = constrained::EvaluateConstrainedRun(c, run);
  for (const char* block :
       {"\"prior\"", "\"optimised\"", "\"prior_on_violating\"", "\"ktm\"", "\"cv\"", "\"naive\"",
        "\"val\"", "\"solve\"", "\"quadrature_accuracy\"", "\"cvp\""})
    EXPECT_NE(json.find(block), std::string::npos) << block;
  EXPECT_EQ(Read(run + "/eval.json"), json);
  // One row per evaluated window after the header.
  const std::string csv = Read(run + "/tracks.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 8);

  const ExperimentKind kind = constrained::Kind();
  // The quadrature chosen on validation windows, midpoints in time, every result checked.
  const std::string checked =
      kind.evaluate(run, {"constraint.time_rule=midpoint", "constraint.choose_quadrature=true",
                          "constraint.choice_windows=4", "constraint.check_order=32",
                          "constraint.choose_check=true"});
  for (const char* key :
       {"\"quadrature_choice\"", "\"truth\"", "\"cvp_converged\"", "\"check_order\"",
        "\"time_rule\": \"midpoint\"", "\"windows_solved_again_after_check\"",
        "\"max_abs_error_vs_continuous_monte_carlo\""})
    EXPECT_NE(checked.find(key), std::string::npos) << key;
  // A check no more accurate than the rule it checks is refused, naming the key.
  ExpectErrorContains([&] { kind.evaluate(run, {"constraint.check_order=6"}); },
                      {"constraint.check_order", "must exceed"});
  for (const char* o : {"map.kind=grid", "seed=3", "split.test_fraction=0.5", "windows.stride=1"})
    ExpectErrorContains([&] { kind.evaluate(run, {o}); }, {o, "train a new run"});
}

TEST(ConstrainedRun, ConfigRulesNameTheKey) {
  ExpectErrorContains(
      [] {
        config::ExperimentConfigFromYaml<constrained::ExperimentConfig>(
            "model: constrained\nnetwork: {u_param: cholesky}\n", "bad.yaml");
      },
      {"bad.yaml", "network.u_param"});
  ExpectErrorContains(
      [] {
        config::ExperimentConfigFromYaml<constrained::ExperimentConfig>(
            "model: constrained\nconstraint: {margin: 0}\n", "bad.yaml");
      },
      {"bad.yaml", "constraint.margin"});
  ExpectErrorContains(
      [] {
        config::ExperimentConfigFromYaml<constrained::ExperimentConfig>(
            "model: constrained\nconstraint: {choose_check: true}\n", "bad.yaml");
      },
      {"bad.yaml", "constraint.choose_check", "choose_quadrature"});
}

}  // namespace
}  // namespace foresight
