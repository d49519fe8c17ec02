// Diffeomorphic templates as a run (thesis ch 8): a resumed run whose last shape lost its baseline
// and artifacts ends with the same models and figures as the uninterrupted one; an obstacle placed
// on the goal is refused with the reason. The engines, learners, data and metrics have their own
// tests (tests/imitation/); the kind's train/export/eval contract is in experiment_test.cc.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "core/config.h"
#include "inference/imitation/eflow.h"
#include "inference/imitation/metrics.h"
#include "inference/imitation/template_artifact.h"
#include "inference/imitation/transforms.h"
#include "tests/test_util.h"
#include "training/diffeo/config.h"
#include "training/diffeo/demos.h"
#include "training/diffeo/eval_common.h"
#include "training/diffeo/pipeline.h"
#include "training/run_dir.h"

namespace foresight {
namespace {
namespace fs = std::filesystem;

imitation::ExperimentConfig Tiny(const std::vector<std::string>& overrides = {}) {
  return config::ExperimentConfigFromYaml<imitation::ExperimentConfig>(
      "model: diffeo\ndata: {source: synthetic, synthetic_demos: 3, synthetic_points: 40, "
      "downsample: 1, held_out: [2]}\nflow: {spacing: 0.1, gamma: 200, cutoff_radius: 0.3, steps: "
      "4}\ntrain: {epochs: 3, batch_size: 32, progress: none}\neflow: {layers: 2, features: 8, "
      "train: {epochs: 3, batch_size: 32, progress: none}}\nobstacle: {times: [0.002, 0.004], "
      "repulsor_gains: [0.1, 1]}\neval: {max_steps: 300, grid: 2, plots: false}\n",
      "<tiny diffeo>", overrides);
}

/// eval.json without its timings (keys ending in _us: one rollout step, measured).
std::string WithoutTimings(const std::string& json) {
  static const std::regex timing(R"re(("[a-z_]*_us"\s*:\s*)[-+0-9.eE]+)re");
  return std::regex_replace(json, timing, "$1<us>");
}

TEST(DiffeoRun, ResumeAfterLosingTheLastArtifactsGivesTheSameModelsAndFigures) {
  const testing::TempDir dir;
  // Time segments and tube samples end to end.
  const imitation::ExperimentConfig c =
      Tiny({"flow.segments=2", "flow.tube_sigma=0.02", "flow.tube_gain=1"});
  const std::string run = dir.File("run");
  ASSERT_TRUE(imitation::TrainRun(c, run, false, nullptr));
  const std::string eval = imitation::EvaluateRun(c, run);
  const auto shape = imitation::LoadTemplate<2>(run + "/models/s_curve.h5");
  const auto eflow = imitation::EFlowModel::Load(run + "/models/s_curve.eflow.h5");
  // As if killed after the flow finished: the baseline's checkpoints and every artifact are gone.
  fs::remove_all(run + "/models");
  fs::remove_all(run + "/shapes/s_curve/eflow");
  fs::remove(run + "/eval.json");
  ASSERT_TRUE(imitation::TrainRun(c, run, true, nullptr));
  EXPECT_EQ(WithoutTimings(imitation::EvaluateRun(c, run)), WithoutTimings(eval));
  const auto shape2 = imitation::LoadTemplate<2>(run + "/models/s_curve.h5");
  const auto eflow2 = imitation::EFlowModel::Load(run + "/models/s_curve.eflow.h5");
  EXPECT_EQ(shape2.system.flow().weights(), shape.system.flow().weights());
  EXPECT_EQ(shape.system.flow().settings().segments, 2);
  EXPECT_EQ(shape2.system.speed(), shape.system.speed());
  const Eigen::Vector2d x(0.2, -0.1);
  EXPECT_EQ(eflow2.Velocity(x), eflow.Velocity(x));
  // A fresh start in the finished directory is refused (naming what is there).
  testing::ExpectErrorContains([&] { imitation::TrainRun(c, run, false, nullptr); }, {run});
}

/// Mean discrete Frechet distance of the template's rollouts from the training demos' starts to
/// those demos (the criterion flow.restarts chooses by), computed here on its own.
double TrainingStartFrechet(const imitation::TemplateArtifact<2>& t,
                            const imitation::PreparedDemos& d,
                            const imitation::ExperimentConfig& c) {
  imitation::RolloutSettings roll;
  roll.dt = c.eval.dt;
  roll.max_steps = c.eval.max_steps;
  roll.goal_tolerance = c.eval.goal_tolerance;
  roll.max_step_length = c.eval.max_step_length;
  auto ws = t.system.flow().MakeWorkspace();
  const auto f = [&](const imitation::Vec<2>& x) { return t.system.Velocity(x, &ws); };
  double sum = 0;
  for (const int i : d.train) {
    const Eigen::MatrixXd& demo = d.demos.demos[static_cast<std::size_t>(i)].position;
    const auto path = imitation::RollOut<2>(f, demo.col(0), t.system.goal(), roll);
    sum += imitation::DiscreteFrechet(imitation::ResampleByArcLength(path.path, 50),
                                      imitation::ResampleByArcLength(demo, 50));
  }
  return sum / static_cast<double>(d.train.size());
}

// flow.restarts: every restart is trained in its own directory, and the exported flow follows
// the training demos at least as well as the single run's (restart 0 is that run).
TEST(DiffeoRun, RestartsExportTheFlowThatFollowsTheTrainingDemosBest) {
  const testing::TempDir dir;
  const std::vector<std::string> common = {"eflow.enabled=false", "obstacle.enabled=false",
                                           "train.epochs=10",     "flow.tube_sigma=0.05",
                                           "flow.tube_gain=2",    "eval.resample=50"};
  std::vector<std::string> three = common;
  three.push_back("flow.restarts=3");
  const imitation::ExperimentConfig c1 = Tiny(common), c3 = Tiny(three);
  const std::string single = dir.File("single"), restarts = dir.File("restarts");
  ASSERT_TRUE(imitation::TrainRun(c1, single, false, nullptr));
  ASSERT_TRUE(imitation::TrainRun(c3, restarts, false, nullptr));
  for (const char* sub : {"flow", "flow_1", "flow_2"})
    EXPECT_TRUE(fs::exists(restarts + "/shapes/s_curve/" + sub + "/checkpoints/best.pt")) << sub;
  EXPECT_FALSE(fs::exists(single + "/shapes/s_curve/flow_1"));
  const imitation::PreparedDemos demos = imitation::LoadDemos(c1).front();
  const auto one = imitation::LoadTemplate<2>(single + "/models/s_curve.h5");
  const auto best = imitation::LoadTemplate<2>(restarts + "/models/s_curve.h5");
  // Here restart 1 wins (0.186 against restart 0's 0.204): strictly better than the single run.
  EXPECT_LT(TrainingStartFrechet(best, demos, c3), TrainingStartFrechet(one, demos, c1) - 0.01);
}

// flow.alternatives: each (time, steps) is trained with the run's seeds as a separate run with
// those settings would be, and the export is the one of them that follows the training demos
// best, with its own time and steps in the artifact.
TEST(DiffeoRun, AlternativesExportTheFlowLengthThatFollowsTheTrainingDemosBest) {
  const testing::TempDir dir;
  const std::vector<std::string> common = {"eflow.enabled=false", "obstacle.enabled=false",
                                           "train.epochs=10",     "flow.tube_sigma=0.05",
                                           "flow.tube_gain=2",    "eval.resample=50"};
  std::vector<std::string> shorter = common, longer = common, both = common;
  shorter.push_back("flow.restarts=2");
  longer.insert(longer.end(), {"flow.restarts=2", "flow.time=2", "flow.steps=8"});
  both.insert(both.end(), {"flow.restarts=2", "flow.alternatives=[{time: 2, steps: 8}]"});
  const imitation::ExperimentConfig c_short = Tiny(shorter), c_long = Tiny(longer),
                                    c_both = Tiny(both);
  ASSERT_EQ(c_both.flow.TotalRestarts(), 4);
  const std::string short_run = dir.File("short"), long_run = dir.File("long"),
                    both_run = dir.File("both");
  ASSERT_TRUE(imitation::TrainRun(c_short, short_run, false, nullptr));
  ASSERT_TRUE(imitation::TrainRun(c_long, long_run, false, nullptr));
  ASSERT_TRUE(imitation::TrainRun(c_both, both_run, false, nullptr));
  // Restart r = v R + k of the combined run is setting v with seed k: it trains exactly as the
  // single-setting runs' restart k (the same losses epoch by epoch; metrics.csv without timings).
  const auto losses = [](const std::string& flow_dir) {
    std::ifstream in(flow_dir + "/metrics.csv");
    std::string line, out;
    while (std::getline(in, line)) {
      std::size_t cut = 0;
      for (int commas = 0; commas < 3 && cut != std::string::npos; ++commas)
        cut = line.find(',', cut == 0 ? 0 : cut + 1);
      out += line.substr(0, cut) + "\n";
    }
    return out;
  };
  const std::string flow = "/shapes/s_curve/flow";
  EXPECT_EQ(losses(both_run + flow), losses(short_run + flow));
  EXPECT_EQ(losses(both_run + flow + "_1"), losses(short_run + flow + "_1"));
  EXPECT_EQ(losses(both_run + flow + "_2"), losses(long_run + flow));
  EXPECT_EQ(losses(both_run + flow + "_3"), losses(long_run + flow + "_1"));
  EXPECT_NE(losses(both_run + flow + "_1"), losses(both_run + flow));  // seeds differ
  EXPECT_GT(losses(both_run + flow + "_3").size(), 20u);
  const imitation::PreparedDemos demos = imitation::LoadDemos(c_short).front();
  const auto a = imitation::LoadTemplate<2>(short_run + "/models/s_curve.h5");
  const auto b = imitation::LoadTemplate<2>(long_run + "/models/s_curve.h5");
  const auto chosen = imitation::LoadTemplate<2>(both_run + "/models/s_curve.h5");
  EXPECT_EQ(a.system.flow().settings().steps, 4);
  EXPECT_EQ(b.system.flow().settings().steps, 8);
  const double fa = TrainingStartFrechet(a, demos, c_short);
  const double fb = TrainingStartFrechet(b, demos, c_long);
  ASSERT_NE(fa, fb);
  const auto& winner = fa <= fb ? a : b;
  EXPECT_EQ(chosen.system.flow().settings().steps, winner.system.flow().settings().steps);
  EXPECT_EQ(chosen.system.flow().settings().time, winner.system.flow().settings().time);
  EXPECT_EQ(chosen.system.flow().weights(), winner.system.flow().weights());
}

TEST(DiffeoConfig, AnAlternativeWithFewerStepsThanSegmentsIsRefused) {
  testing::ExpectErrorContains(
      [] {
        Tiny({"flow.segments=3", "flow.alternatives=[{time: 1, steps: 2}]"});
      },
      {"flow.alternatives[0].steps", "flow.segments"});
}

TEST(DiffeoSelection, TakesTheFirstTrainingClearSettingWithTheFewestGridCrossings) {
  using imitation::ChooseClearance;
  using C = imitation::Clearance;
  // Training starts clear from index 1; crossings 3, 1, 1, 2: the first of the two 1s.
  EXPECT_EQ(ChooseClearance({C{false, 0}, C{true, 3}, C{true, 1}, C{true, 1}, C{true, 2}}), 2u);
  // A setting whose training starts are not clear never wins, however few its crossings.
  EXPECT_EQ(ChooseClearance({C{true, 4}, C{false, 0}, C{true, 4}}), 0u);
  // The first training-clear setting with none crossing.
  EXPECT_EQ(ChooseClearance({C{false, 2}, C{true, 0}}), 1u);
  // No setting clears the training starts: the last one tried (the strongest), as before the grid.
  EXPECT_EQ(ChooseClearance({C{false, 0}, C{false, 5}, C{false, 1}}), 2u);
  EXPECT_EQ(ChooseClearance({C{false, 0}}), 0u);
}

TEST(DiffeoSelection, TaskSpaceFlowTimeTakesTheCoarsestStepThatInverts) {
  using imitation::ChooseFlowTime;
  using imitation::FlowTrial;
  const std::vector<double> times{0.1, 0.2, 0.4, 0.8};
  std::vector<std::pair<double, double>> tried;
  // A map inverts when time x step <= 4e-4 (the longer the flow, the finer the step it needs), and
  // clears from time 0.4 on.
  const auto trial = [&](double t, double step) {
    tried.emplace_back(t, step);
    FlowTrial f;
    f.inverts = t * step <= 4e-4 * (1 + 1e-9);
    f.clear = f.inverts && t >= 0.4;
    return f;
  };
  // Step 0.002: 0.1 and 0.2 invert, 0.4 needs one halving (0.001), and clears there.
  auto pick = ChooseFlowTime(times, 0.002, 3, trial);
  EXPECT_EQ(pick.index, 2);
  EXPECT_DOUBLE_EQ(pick.step, 0.001);
  EXPECT_TRUE(pick.cleared);
  ASSERT_EQ(tried.size(), 4u);  // 0.1, 0.2 at 0.002; 0.4 at 0.002 then 0.001
  EXPECT_DOUBLE_EQ(tried[2].second, 0.002);
  EXPECT_DOUBLE_EQ(tried[3].second, 0.001);
  // No halvings: 0.4 does not invert, so 0.2 is kept at the first step, not cleared.
  tried.clear();
  pick = ChooseFlowTime(times, 0.002, 0, trial);
  EXPECT_EQ(pick.index, 1);
  EXPECT_DOUBLE_EQ(pick.step, 0.002);
  EXPECT_FALSE(pick.cleared);
  // The halvings are counted over all times: with one left after 0.4, a map that never clears
  // stops at the first time that does not invert with none left.
  const auto never_clear = [&](double t, double step) {
    FlowTrial f = trial(t, step);
    f.clear = false;
    return f;
  };
  pick = ChooseFlowTime(times, 0.002, 2, never_clear);
  EXPECT_EQ(pick.index, 3);  // 0.4 at 0.001, 0.8 at 0.0005 (two halvings)
  EXPECT_DOUBLE_EQ(pick.step, 0.0005);
  pick = ChooseFlowTime(times, 0.002, 1, never_clear);
  EXPECT_EQ(pick.index, 2);
  EXPECT_DOUBLE_EQ(pick.step, 0.001);
  // The first time does not invert at any step: nothing chosen.
  pick = ChooseFlowTime({5.0}, 0.002, 2, trial);
  EXPECT_EQ(pick.index, -1);
}

TEST(DiffeoRun, AnObstacleOnTheGoalIsRefused) {
  const testing::TempDir dir;
  const imitation::ExperimentConfig c = Tiny({"obstacle.fraction=1.0"});
  const std::string run = dir.File("run");
  ASSERT_TRUE(imitation::TrainRun(c, run, false, nullptr));
  testing::ExpectErrorContains([&] { imitation::EvaluateRun(c, run); },
                               {"s_curve", "covers the goal", "obstacle.fraction"});
}

TEST(DiffeoDemos, ExcludedDemosAreDroppedAndHeldOutIsRenumbered) {
  // Both train on demo 1 alone, so they share the normalisation: A's demos are B's 1 and 2.
  const auto a = imitation::LoadDemos(Tiny({"data.excluded=[0]"}));
  const auto b = imitation::LoadDemos(Tiny({"data.held_out=[0, 2]"}));
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(a[0].demos.demos.size(), 2u);
  EXPECT_EQ(a[0].train, std::vector<int>{0});
  EXPECT_EQ(a[0].held_out, std::vector<int>{1});
  EXPECT_EQ(a[0].original, (std::vector<int>{1, 2}));
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(a[0].demos.demos[k].position, b[0].demos.demos[k + 1].position) << k;
    EXPECT_EQ(a[0].demos.demos[k].velocity, b[0].demos.demos[k + 1].velocity) << k;
  }
  testing::ExpectErrorContains([] { imitation::LoadDemos(Tiny({"data.excluded=[3]"})); },
                               {"s_curve", "data.excluded", "demo 3", "3 demos"});
  testing::ExpectErrorContains([] { imitation::LoadDemos(Tiny({"data.excluded=[0, 1]"})); },
                               {"s_curve", "no demo left to train on"});
}

TEST(DiffeoConfig, RulesAcrossKeysNameTheKey) {
  testing::ExpectErrorContains([] { Tiny({"data.excluded=[2]"}); },
                               {"demo 2", "data.held_out", "data.excluded"});
  testing::ExpectErrorContains([] { Tiny({"data.excluded=[-1]"}); }, {"data.excluded", "negative"});
  testing::ExpectErrorContains([] { Tiny({"data.held_out=[1, 1]"}); }, {"data.held_out", "twice"});
  testing::ExpectErrorContains([] { Tiny({"obstacle.times=[0.004, 0.002]"}); },
                               {"obstacle.times", "not increasing"});
  testing::ExpectErrorContains([] { Tiny({"data.task=stack_box"}); }, {"data.task", "stack_box"});
  testing::ExpectErrorContains([] { Tiny({"flow.segments=5"}); },
                               {"flow.segments (5)", "flow.steps (4)"});
  testing::ExpectErrorContains(
      [] {
        Tiny({"bias.enabled=true", "bias.target=[0.1]"});
      },
      {"bias.target", "expected 2"});
}

}  // namespace
}  // namespace foresight
