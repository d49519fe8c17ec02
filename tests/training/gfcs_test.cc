// Self-supervised GFCS (thesis ch 9): the InfoNCE loss against its definition, the LibTorch
// energy network against the engine that runs it, and the loop's resume (a run stopped at an
// arbitrary solve and continued ends with the same model as an uninterrupted one).

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <thread>

#include "core/config.h"
#include "inference/manipulation/energy_model.h"
#include "models/gfcs/gfcs_nets.h"
#include "tests/test_util.h"
#include "training/gfcs/config.h"
#include "training/gfcs/loop.h"
#include "training/gfcs/pipeline.h"

namespace foresight {
namespace {
namespace fs = std::filesystem;

TEST(InfoNce, MatchesTheDefinitionPerPositive) {
  torch::manual_seed(3);
  const torch::Tensor pos = torch::randn({5}, torch::kFloat64);
  const torch::Tensor neg = torch::randn({5, 7}, torch::kFloat64) * 2;
  double expected = 0;
  for (int j = 0; j < 5; ++j) {
    // -log(e^{-E+} / (e^{-E+} + sum_k e^{-E-_k})), thesis eq. "lossimpli" with the errata's sign.
    double denominator = std::exp(-pos[j].item<double>());
    for (int k = 0; k < 7; ++k) denominator += std::exp(-neg[j][k].item<double>());
    expected += -std::log(std::exp(-pos[j].item<double>()) / denominator) / 5;
  }
  EXPECT_NEAR(gfcs::InfoNceLoss(pos, neg).item<double>(), expected, 1e-12);
  // Lower positive energy is better: the loss falls when E+ falls.
  EXPECT_LT(gfcs::InfoNceLoss(pos - 1, neg).item<double>(),
            gfcs::InfoNceLoss(pos, neg).item<double>());
}

TEST(InfoNce, AMaskedNegativeIsAsIfAbsentInTheLossAndItsGradient) {
  torch::manual_seed(4);
  const torch::Tensor pos = torch::randn({3}, torch::kFloat64).requires_grad_();
  const torch::Tensor neg = (torch::randn({3, 5}, torch::kFloat64) * 2).requires_grad_();
  // Row j keeps its first 5 - j negatives (row 2: three).
  torch::Tensor valid = torch::ones({3, 5}, torch::kBool);
  for (int j = 1; j < 3; ++j) valid[j].slice(0, 5 - j, 5).fill_(false);
  const torch::Tensor masked = gfcs::InfoNceLoss(pos, neg, valid);
  masked.backward();
  // The same rows without their masked negatives, one by one (each row's loss over 3 rows).
  double expected = 0;
  for (int j = 0; j < 3; ++j) {
    const torch::Tensor p = pos.detach()[j].unsqueeze(0);
    const torch::Tensor n = neg.detach()[j].slice(0, 0, 5 - j).unsqueeze(0);
    expected += gfcs::InfoNceLoss(p, n).item<double>() / 3;
  }
  EXPECT_NEAR(masked.item<double>(), expected, 1e-12);
  // No gradient reaches a masked negative; the others' is finite.
  EXPECT_TRUE(torch::isfinite(neg.grad()).all().item<bool>());
  EXPECT_TRUE(torch::isfinite(pos.grad()).all().item<bool>());
  EXPECT_EQ(neg.grad().masked_select(valid.logical_not()).abs().max().item<double>(), 0.0);
  EXPECT_GT(neg.grad().masked_select(valid).abs().min().item<double>(), 0.0);
  // An all-true mask is the unmasked loss.
  EXPECT_NEAR(gfcs::InfoNceLoss(pos.detach(), neg.detach(), torch::ones({3, 5}, torch::kBool))
                  .item<double>(),
              gfcs::InfoNceLoss(pos.detach(), neg.detach()).item<double>(), 1e-15);
  EXPECT_THROW(gfcs::InfoNceLoss(pos.detach(), neg.detach(), torch::ones({3, 4}, torch::kBool)),
               Error);
}

TEST(EnergyNet, TheEngineComputesWhatLibTorchTrained) {
  torch::manual_seed(5);
  const int encoding = 6, commands = 14, context = 21 + encoding;
  gfcs::EnergyNet net(context, commands, 32, 3);
  manipulation::EnergyModelParts parts;
  parts.lattice.spacing = 1.0;
  const int n_r = parts.lattice.size();
  parts.bps_mean = Eigen::VectorXf::Zero(n_r);
  parts.bps_std = Eigen::VectorXf::Ones(n_r);
  DenseLayer enc;
  enc.weight = Eigen::MatrixXf::Random(encoding, n_r);
  enc.bias = Eigen::VectorXf::Zero(encoding);
  parts.encoder = Mlp({enc});
  parts.energy = net->net()->ToMlp();
  parts.intermediate_commands = 2;
  const manipulation::EnergyModel model(parts);

  const torch::Tensor ctx = torch::randn({1, context});
  const torch::Tensor u = torch::rand({1, 9, commands}) * 2 - 1;
  const torch::Tensor e = net->forward(ctx, u);  // [1, 9]
  Eigen::VectorXf c(context), energy;
  for (int i = 0; i < context; ++i) c[i] = ctx[0][i].item<float>();
  Eigen::MatrixXf uu(commands, 9), grad;
  for (int k = 0; k < 9; ++k)
    for (int d = 0; d < commands; ++d) uu(d, k) = u[0][k][d].item<float>();
  auto ws = model.MakeWorkspace(9);
  model.EnergyAndGradient(c, uu, &energy, &grad, &ws);
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(energy[k], e[0][k].item<float>(), 1e-5) << k;

  // The round trip through engine weights keeps the network.
  gfcs::EnergyNet copy(context, commands, 32, 3);
  copy->net()->LoadMlp(parts.energy);
  EXPECT_TRUE(torch::allclose(copy->forward(ctx, u), e));
}

/// The tiny self-supervised run of these tests (built-in Panda, generated scenes).
gfcs::ExperimentConfig TinyConfig() {
  return config::ExperimentConfigFromYaml<gfcs::ExperimentConfig>(
      "model: gfcs\nrobot: builtin\ntrain_problems: [{source: synthetic, synthetic_count: 3}]\n"
      "lattice: {spacing: 0.6}\nautoencoder: {encoding: 4, hidden: 8, train: {epochs: 3, "
      "batch_size: 2, progress: none}}\nenergy: {hidden: 16, layers: 2}\nloop: {passes: 2, "
      "train_every: 2, adam_steps: 4, learning_rate: 0.01, negatives: 3, negative_sgld: {steps: "
      "3}, batches: 2, batch_size: 6}\nsampler: {particles: 6, steps: 3}\neval: {problems: "
      "[{source: "
      "synthetic, synthetic_seed: 100, synthetic_count: 2}]}\n",
      "<tiny gfcs>");
}

std::vector<Eigen::MatrixXf> EnergyWeights(const std::string& artifact) {
  const manipulation::EnergyModel model = manipulation::EnergyModel::Load(artifact);
  std::vector<Eigen::MatrixXf> out;
  for (const DenseLayer& l : model.parts().energy.layers()) out.push_back(l.weight);
  return out;
}

/// The solution memories of two artifacts are equal, bit for bit.
void ExpectTheSameMemory(const std::string& artifact_a, const std::string& artifact_b) {
  const manipulation::EnergyModel a = manipulation::EnergyModel::Load(artifact_a);
  const manipulation::EnergyModel b = manipulation::EnergyModel::Load(artifact_b);
  const manipulation::SolutionMemory &ma = a.parts().memory, &mb = b.parts().memory;
  ASSERT_FALSE(ma.empty());
  ASSERT_EQ(ma.problem.size(), mb.problem.size());
  ASSERT_EQ(ma.contexts.cols(), mb.contexts.cols());
  EXPECT_EQ(ma.problem, mb.problem);
  EXPECT_EQ(ma.cost, mb.cost);
  EXPECT_EQ(ma.commands, mb.commands);
  EXPECT_EQ(ma.contexts, mb.contexts);
}

TEST(GfcsLoop, AResumedRunEndsWithTheModelOfAnUninterruptedOne) {
  gfcs::ExperimentConfig c = TinyConfig();
  c.loop.failure_negatives = 2;  // the kept failures are loop state too
  testing::TempDir dir;
  const std::string whole = dir.File("whole"), broken = dir.File("broken");
  ASSERT_TRUE(gfcs::TrainRun(c, whole, false, nullptr));

  // Stop the second run as soon as its loop has written a checkpoint (some solve, not chosen).
  std::atomic<bool> stop{false};
  std::thread watcher([&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (!fs::exists(gfcs::LoopCheckpointPath(broken, 0)) &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    stop = true;
  });
  const bool finished = gfcs::TrainRun(c, broken, false, &stop);
  watcher.join();
  EXPECT_FALSE(finished) << "the run was stopped before its end";
  ASSERT_TRUE(gfcs::TrainRun(c, broken, true, nullptr));

  const auto a = EnergyWeights(whole + "/model.h5"), b = EnergyWeights(broken + "/model.h5");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].isApprox(b[i], 1e-6f)) << i;
  const std::string summary = testing::ReadText(whole + "/loop_summary.json");
  EXPECT_NE(summary.find("\"solves\": 6"), std::string::npos) << summary;
  // The sampler's failures were kept and trained against: at most 2 per solve.
  const auto kept_at = summary.find("\"failures_kept\": ");
  ASSERT_NE(kept_at, std::string::npos) << summary;
  const int kept = std::atoi(summary.c_str() + kept_at + 17);
  EXPECT_GT(kept, 0) << summary;
  EXPECT_LE(kept, 2 * 6);
  // ... and some round filled failure slots (each round logs "(+ F of S failure slots filled)").
  const std::string log = testing::ReadText(whole + "/log.txt");
  int filled = 0;
  for (auto at = log.find("(+ "); at != std::string::npos; at = log.find("(+ ", at + 1))
    filled += std::atoi(log.c_str() + at + 3);
  EXPECT_GT(filled, 0) << log;
  // The solution memory holds every solution found, beyond the buffer, the same after a resume.
  ExpectTheSameMemory(whole + "/model.h5", broken + "/model.h5");
  // The held-out evaluation runs the nearest-neighbour sampler on that memory beside the learned
  // one, with both paired comparisons.
  const std::string eval = gfcs::EvaluateRun(c, whole);
  for (const char* key :
       {"\"GFCS nearest (1 batch)\"", "\"nearest_minus_uniform\"", "\"learned_minus_nearest\""})
    EXPECT_NE(eval.find(key), std::string::npos) << key;

  // A checkpoint from another config is refused with the key that differs.
  gfcs::ExperimentConfig other = c;
  other.loop.adam_steps = 5;
  gfcs::Encoding enc;
  Mlp energy;
  manipulation::SolutionMemory memory;
  testing::ExpectErrorContains(
      [&] { gfcs::LoadLoopResult(other, config::ToYaml(other), whole, &enc, &energy, &memory); },
      {"another config", "adam_steps: 5"});
}

/// `command` in bash; its exit status.
int Shell(const std::string& command) {
  const int s = std::system(("bash -c '" + command + "'").c_str());
  return WIFEXITED(s) ? WEXITSTATUS(s) : 128;
}

/// The energy layers of two artifacts are equal, bit for bit.
void ExpectTheSameEnergyNet(const std::string& artifact_a, const std::string& artifact_b) {
  const auto a = EnergyWeights(artifact_a), b = EnergyWeights(artifact_b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ((a[i] - b[i]).cwiseAbs().maxCoeff(), 0.0f) << "layer " << i;
}

/// Relaunches both ranks of `command` (env + CLI call) in `d` with --resume through a fresh
/// FileStore; the OR of their exit statuses (outputs in d/q0.out, d/q1.out).
int ResumeTwoRanks(const std::string& d, const std::string& command) {
  return Shell("cd " + d + " && (FORESIGHT_STORE_FILE=" + d + "/s2 RANK=0 " + command +
               " --resume > q0.out 2>&1 & p0=$!; FORESIGHT_STORE_FILE=" + d + "/s2 RANK=1 " +
               command +
               " --resume > q1.out 2>&1 & p1=$!; wait $p0; a=$?; wait $p1; b=$?; exit $((a | b)))");
}

/// Writes `c` to d/tiny.yaml and trains it on one rank into d/one (the reference model);
/// whether that run succeeded (its output in d/one.out).
::testing::AssertionResult TrainTheReferenceOnOneRank(const gfcs::ExperimentConfig& c,
                                                      const std::string& d) {
  testing::WriteText(d + "/tiny.yaml", config::ToYaml(c));
  const std::string cli = FORESIGHT_CLI;
  if (Shell("cd " + d + " && timeout 120 " + cli +
            " train tiny.yaml --run-dir one --no-eval > one.out 2>&1") == 0)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << testing::ReadText(d + "/one.out");
}

TEST(GfcsLoop, TwoRanksShareTheSolvesAndEndWithTheModelOfOne) {
  gfcs::ExperimentConfig c = TinyConfig();
  c.loop.threads = 1;
  c.autoencoder.train.threads = 1;
  c.loop.gradient_shards = 2;  // the training rounds data-parallel too: one shard per rank
  testing::TempDir dir;
  const std::string cli = FORESIGHT_CLI, d = dir.path();
  ASSERT_TRUE(TrainTheReferenceOnOneRank(c, d));
  const std::string rank = "FORESIGHT_STORE_FILE=" + d +
                           "/store FORESIGHT_DIST_TIMEOUT_S=60 WORLD_SIZE=2 timeout 120 " + cli +
                           " train tiny.yaml --run-dir two --no-eval";
  ASSERT_EQ(Shell("cd " + d + " && (RANK=0 " + rank + " > r0.out 2>&1 & p0=$!; RANK=1 " + rank +
                  " > r1.out 2>&1 & p1=$!; wait $p0; a=$?; wait $p1; b=$?; exit $((a | b)))"),
            0)
      << testing::ReadText(d + "/r0.out") << testing::ReadText(d + "/r1.out");
  // Rank 1 solved its share (every other solve of a block) and kept its own checkpoint; the
  // rounds' losses are the same float sums as on one rank.
  const std::string log1 = testing::ReadText(d + "/two/log.rank1.txt");
  EXPECT_NE(log1.find("solve 2/6"), std::string::npos);
  const std::string round = "training round 3: ";
  const auto Round3 = [&](const std::string& log) {
    const auto at = log.find(round);
    return at == std::string::npos ? std::string() : log.substr(at, log.find('\n', at) - at);
  };
  EXPECT_FALSE(Round3(log1).empty()) << log1;
  EXPECT_EQ(Round3(log1), Round3(testing::ReadText(d + "/one/log.txt")));
  EXPECT_TRUE(fs::exists(gfcs::LoopCheckpointPath(d + "/two", 1)));
  ExpectTheSameEnergyNet(d + "/one/model.h5", d + "/two/model.h5");
  ExpectTheSameMemory(d + "/one/model.h5", d + "/two/model.h5");
}

TEST(GfcsLoop, TwoRanksKilledMidRunResumeToTheModelOfOne) {
  gfcs::ExperimentConfig c = TinyConfig();
  c.loop.threads = 1;
  c.autoencoder.train.threads = 1;
  c.loop.passes = 4;             // 12 solves, 6 blocks
  c.loop.failure_negatives = 2;  // kept failures are gathered, checkpointed and resumed alike
  testing::TempDir dir;
  const std::string cli = FORESIGHT_CLI, d = dir.path();
  ASSERT_TRUE(TrainTheReferenceOnOneRank(c, d));
  // Rank 1 is killed as soon as its loop checkpoint shows a few solves; rank 0 then fails (a short
  // collective timeout) wherever it was. Both are relaunched with --resume.
  const std::string env = "FORESIGHT_DIST_TIMEOUT_S=5 WORLD_SIZE=2 ";
  const std::string run = " timeout 120 " + cli + " train tiny.yaml --run-dir two --no-eval";
  const std::string bare = " " + cli + " train tiny.yaml --run-dir two --no-eval";  // killable
  Shell("cd " + d + " && (FORESIGHT_STORE_FILE=" + d + "/s1 RANK=0 " + env + run +
        " > r0.out 2>&1 & FORESIGHT_STORE_FILE=" + d + "/s1 RANK=1 " + env + bare +
        " > r1.out 2>&1 & p1=$!; for i in $(seq 2000); do grep -q \"solve 4/\" two/log.rank1.txt "
        "2>/dev/null && break; sleep 0.005; done; kill -9 $p1; wait)");
  if (testing::ReadText(d + "/r0.out").find("error: rank 0 of 2") == std::string::npos)
    GTEST_SKIP()
        << "rank 1 finished before the kill reached it (a loaded machine): nothing to resume";
  const int resumed = ResumeTwoRanks(d, env + run);
  ASSERT_EQ(resumed, 0) << testing::ReadText(d + "/r0.out") << testing::ReadText(d + "/q0.out")
                        << testing::ReadText(d + "/q1.out");
  ExpectTheSameEnergyNet(d + "/one/model.h5", d + "/two/model.h5");
  ExpectTheSameMemory(d + "/one/model.h5", d + "/two/model.h5");
}

TEST(GfcsLoop, ASignalToOneRankStopsBothAndTheyResumeToTheModelOfOne) {
  gfcs::ExperimentConfig c = TinyConfig();
  c.loop.threads = 1;
  c.autoencoder.train.threads = 1;
  c.loop.passes = 4;       // 12 solves
  c.loop.train_every = 6;  // blocks of 3 solves per rank: the stop flag, not the block end, stops
  testing::TempDir dir;
  const std::string cli = FORESIGHT_CLI, d = dir.path();
  ASSERT_TRUE(TrainTheReferenceOnOneRank(c, d));
  // SIGTERM to rank 0 only, once its log shows a few solves; rank 1 must stop too (the flag in
  // the store), not fail on a lost peer and not run on to the end.
  const std::string env = "FORESIGHT_DIST_TIMEOUT_S=60 WORLD_SIZE=2 ";
  const std::string run = " timeout 120 " + cli + " train tiny.yaml --run-dir two --no-eval";
  const std::string bare = " " + cli + " train tiny.yaml --run-dir two --no-eval";  // signalled
  Shell("cd " + d + " && (FORESIGHT_STORE_FILE=" + d + "/s1 RANK=0 " + env + bare +
        " > r0.out 2>&1 & p0=$!; FORESIGHT_STORE_FILE=" + d + "/s1 RANK=1 " + env + run +
        " > r1.out 2>&1 & for i in $(seq 2000); do grep -q \"solve 3/\" two/log.txt "
        "2>/dev/null && break; sleep 0.005; done; kill -TERM $p0; wait)");
  const std::string r0 = testing::ReadText(d + "/r0.out"), r1 = testing::ReadText(d + "/r1.out");
  if (r0.find("interrupted") == std::string::npos)
    GTEST_SKIP() << "rank 0 finished before the signal reached it (a loaded machine)";
  EXPECT_NE(r1.find("interrupted; continue with --resume"), std::string::npos) << r1;
  EXPECT_EQ(r1.find("failed"), std::string::npos) << r1;
  EXPECT_FALSE(fs::exists(d + "/two/model.h5"));
  const int resumed = ResumeTwoRanks(d, env + run);
  ASSERT_EQ(resumed, 0) << testing::ReadText(d + "/q0.out") << testing::ReadText(d + "/q1.out");
  ExpectTheSameEnergyNet(d + "/one/model.h5", d + "/two/model.h5");
  ExpectTheSameMemory(d + "/one/model.h5", d + "/two/model.h5");
}

TEST(GfcsConfig, HeldOutProblemsMayNotOverlapTheTrainingOnes) {
  testing::ExpectErrorContains(
      [] {
        (void)config::ExperimentConfigFromYaml<gfcs::ExperimentConfig>(
            "model: gfcs\ntrain_problems: [{family: box_panda, first: 1, last: 50}]\n"
            "eval: {problems: [{family: box_panda, first: 40, last: 60}]}\n",
            "overlap.yaml");
      },
      {"overlap.yaml", "eval.problems", "overlaps"});
  testing::ExpectErrorContains(
      [] {
        (void)config::ExperimentConfigFromYaml<gfcs::ExperimentConfig>(
            "model: gfcs\ngfcs: {commands: 1}\n", "one.yaml");
      },
      {"one.yaml", "gfcs.commands"});
}

// Paired learned-minus-uniform values are per problem, each the mean over the problem's draws.
TEST(GfcsEval, PairedDifferencesAverageEachProblemsDraws) {
  std::vector<manipulation::PlanAttempt> attempts;
  const auto add = [&](const char* method, int problem, int repeat, bool success, double time,
                       std::optional<double> cost, const char* status = "solved") {
    manipulation::PlanAttempt a;
    a.method = method;
    a.problem = problem;
    a.repeat = repeat;
    a.status = status;
    a.metrics.success = success;
    a.metrics.time_s = time;
    a.gfcs_cost = cost;
    attempts.push_back(a);
  };
  // Problem 1, two draws: learned solves both, uniform the first only.
  add("U", 1, 0, true, 1.0, 3.0);
  add("L", 1, 0, true, 2.0, 2.0);
  add("U", 1, 1, false, 1.0, 100.0, "timeout");
  add("L", 1, 1, true, 4.0, 5.0);
  // Problem 2, two draws: uniform solves both, learned errors on the second (no time, no cost).
  add("U", 2, 0, true, 1.0, 4.0);
  add("L", 2, 0, false, 3.0, 100.0, "timeout");
  add("U", 2, 1, true, 2.0, 6.0);
  add("L", 2, 1, false, 0.0, std::nullopt, "error: bad");
  // Problem 3: only uniform ran (not paired); another method is ignored.
  add("U", 3, 0, true, 1.0, 1.0);
  add("X", 1, 0, false, 9.0, 9.0);
  const gfcs::PairedPerProblem p = gfcs::PairPerProblem(attempts, "U", "L");
  ASSERT_EQ(p.success.size(), 2u);
  EXPECT_DOUBLE_EQ(p.success[0], 0.5);   // (0 + 1) / 2
  EXPECT_DOUBLE_EQ(p.success[1], -1.0);  // (-1 - 1) / 2
  ASSERT_EQ(p.time.size(), 2u);
  EXPECT_DOUBLE_EQ(p.time[0], 2.0);  // (1 + 3) / 2
  EXPECT_DOUBLE_EQ(p.time[1], 2.0);  // the errored draw left out
  ASSERT_EQ(p.cost.size(), 2u);
  EXPECT_DOUBLE_EQ(p.cost[0], (-1.0 - 95.0) / 2);
  EXPECT_DOUBLE_EQ(p.cost[1], 96.0);
  ASSERT_EQ(p.cost_solved.size(), 1u);  // problem 1's first draw only
  EXPECT_DOUBLE_EQ(p.cost_solved[0], -1.0);
  EXPECT_EQ(p.only_learned, 1);
  EXPECT_EQ(p.only_uniform, 2);
}

}  // namespace
}  // namespace foresight
