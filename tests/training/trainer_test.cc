#include "training/trainer.h"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "core/h5.h"
#include "models/span/span_net.h"
#include "tests/test_util.h"
#include "training/span/eval.h"
#include "training/span/pipeline.h"

namespace foresight {
namespace {

span::ExperimentConfig TinyConfig() {
  span::ExperimentConfig c;
  c.data.synthetic.num_tracks = 120;
  c.network.hidden = {16, 16};
  c.basis.num_centres = 5;
  c.train.epochs = 4;
  c.train.batch_size = 64;
  c.train.progress = ProgressStyle::kNone;
  c.train.patience = 0;
  return c;
}

std::vector<torch::Tensor> Parameters(const std::string& checkpoint,
                                      const span::ExperimentConfig& c) {
  span::Net net(2 * c.windows.observed, c.network,
                HeadLayout{c.basis.num_centres, c.network.components, c.network.u_param});
  LoadCheckpointModel(checkpoint, net.ptr().get());
  std::vector<torch::Tensor> out;
  for (const auto& p : net->parameters()) out.push_back(p.detach().clone());
  return out;
}

/// Epoch, train and validation loss columns of metrics.csv (timings differ run to run).
std::string LossColumns(const std::string& path) {
  std::ifstream in(path);
  std::string line, out;
  while (std::getline(in, line)) {
    std::size_t third = line.find(',', line.find(',', line.find(',') + 1) + 1);
    out += line.substr(0, third) + "\n";
  }
  return out;
}

TEST(Trainer, ResumeAfterAnInterruptionIsBitIdentical) {
  testing::TempDir dir;
  const span::ExperimentConfig c = TinyConfig();
  const auto full = span::TrainRun(c, dir.File("full"), false);
  EXPECT_EQ(full.reason, TerminationReason::kMaxEpochs);
  EXPECT_EQ(full.epochs_completed, 4);

  TrainHooks stop_after_two;
  stop_after_two.continue_after_epoch = [](int completed) { return completed < 2; };
  const auto first = span::TrainRun(c, dir.File("resumed"), false, stop_after_two);
  EXPECT_EQ(first.reason, TerminationReason::kInterrupted);
  EXPECT_EQ(first.epochs_completed, 2);
  const auto second = span::TrainRun(c, dir.File("resumed"), true);
  EXPECT_EQ(second.reason, TerminationReason::kMaxEpochs);
  EXPECT_EQ(second.epochs_completed, 4);

  const auto a = Parameters(dir.File("full") + "/checkpoints/last.pt", c);
  const auto b = Parameters(dir.File("resumed") + "/checkpoints/last.pt", c);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_TRUE(torch::equal(a[i], b[i])) << "parameter " << i;
  EXPECT_EQ(LossColumns(dir.File("full") + "/metrics.csv"),
            LossColumns(dir.File("resumed") + "/metrics.csv"));
}

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Stops a run after `epochs` completed epochs.
TrainHooks StopAfter(int epochs) {
  TrainHooks hooks;
  hooks.continue_after_epoch = [epochs](int completed) { return completed < epochs; };
  return hooks;
}

/// A one-parameter task whose validation loss is negative (as a well-trained NLL is): minimises
/// (p - 3)^2 with a validation loss of (p - 3)^2 - 10.
class NegativeLossTask : public TrainingTask {
 public:
  NegativeLossTask() { p_ = module_.register_parameter("p", torch::zeros({1})); }
  torch::nn::Module& module() override { return module_; }
  std::int64_t num_train() const override { return 8; }
  torch::Tensor BatchLoss(const torch::Tensor&) override { return (p_ - 3.0).pow(2).sum(); }
  double ValidationLoss() override { return (p_ - 3.0).pow(2).sum().item<double>() - 10.0; }

 private:
  torch::nn::Module module_;
  torch::Tensor p_;
};

// Issue 18, defect 1, at its root: a negative best validation loss read back as a reinterpreted
// int64 (-8.5 became -4.6e18), so no epoch after a resume was ever "best" again.
TEST(Trainer, ResumeKeepsANegativeBestValidationLoss) {
  testing::TempDir dir;
  TrainConfig c;
  c.epochs = 6;
  c.batch_size = 4;
  c.learning_rate = 0.1;
  c.patience = 0;
  c.progress = ProgressStyle::kNone;
  NegativeLossTask full_task;
  const TrainingSummary full = Train(&full_task, c, RunPaths{dir.File("full")}, 1, false);
  NegativeLossTask first, second;
  Train(&first, c, RunPaths{dir.File("resumed")}, 1, false, StopAfter(2));
  const TrainingSummary resumed = Train(&second, c, RunPaths{dir.File("resumed")}, 1, true);
  ASSERT_LT(full.best_val_loss, 0.0);
  EXPECT_EQ(full.best_epoch, 6);
  EXPECT_EQ(resumed.best_epoch, full.best_epoch);
  EXPECT_EQ(resumed.best_val_loss, full.best_val_loss);
  NegativeLossTask a, b;
  LoadCheckpointModel(dir.File("full/checkpoints/best.pt"), &a.module());
  LoadCheckpointModel(dir.File("resumed/checkpoints/best.pt"), &b.module());
  EXPECT_TRUE(torch::equal(a.module().parameters()[0], b.module().parameters()[0]));
}

/// What a span_predictor artifact holds (weights, normalisation, basis, the /model attributes of
/// its schema, config, seed); HDF5 timestamps aside, two equal digests mean the same model.
std::string ArtifactDigest(const std::string& path) {
  const h5::File f = h5::File::Open(path);
  std::ostringstream os;
  os.precision(17);
  os << f.ReadString("/config") << "\n" << f.GetIntAttr("/", "seed") << "\n";
  for (const char* name : {"observed", "predicted", "rotate_to_heading",
                           "residual_to_constant_velocity", "basis_size", "components"})
    os << name << " " << f.GetIntAttr("/model", name) << "\n";
  for (const char* name : {"seconds_per_step", "basis_gamma"})
    os << name << " " << f.GetDoubleAttr("/model", name) << "\n";
  for (const char* name : {"u_param", "dense_layers"})
    os << name << " " << f.GetStringAttr("/model", name) << "\n";
  for (const std::string group : {"/weights", "/normalisation", "/model"}) {
    std::vector<std::string> pending{group};
    while (!pending.empty()) {
      const std::string g = pending.back();
      pending.pop_back();
      for (const auto& name : f.List(g)) {
        const std::string full = g + "/" + name;
        try {
          const auto a = f.ReadDouble(full);
          os << full << ":";
          for (double v : a.data) os << " " << v;
          os << "\n";
        } catch (const Error&) {
          pending.push_back(full);  // a group
        }
      }
    }
  }
  return os.str();
}

// Issue 18, defect 1: a resumed run read its best validation loss back as a reinterpreted int64,
// so best.pt was never replaced after a resume and the export was an older model. The whole
// pipeline (train, export, eval) of a resumed run must match the uninterrupted one exactly.
TEST(Trainer, ResumedRunExportsAndEvaluatesTheSameModelAsAnUninterruptedOne) {
  testing::TempDir dir;
  span::ExperimentConfig c = TinyConfig();
  c.train.epochs = 8;
  c.train.patience = 3;
  c.eval.plot_tracks = 0;
  const auto full = span::TrainRun(c, dir.File("full"), false);
  span::TrainRun(c, dir.File("resumed"), false, StopAfter(2));
  const auto resumed = span::TrainRun(c, dir.File("resumed"), true);
  ASSERT_GT(full.best_epoch, 2) << "the test needs a best epoch after the interruption";
  EXPECT_EQ(resumed.reason, full.reason);
  EXPECT_EQ(resumed.epochs_completed, full.epochs_completed);
  EXPECT_EQ(resumed.best_epoch, full.best_epoch);
  EXPECT_EQ(resumed.best_val_loss, full.best_val_loss);

  const std::string a = span::ExportRun(dir.File("full"));
  const std::string b = span::ExportRun(dir.File("resumed"));
  EXPECT_EQ(ArtifactDigest(a), ArtifactDigest(b));
  span::Evaluate(c, a, dir.File("full"));
  span::Evaluate(c, b, dir.File("resumed"));
  EXPECT_EQ(testing::ReadText(dir.File("full/eval.json")),
            testing::ReadText(dir.File("resumed/eval.json")));
}

TEST(Trainer, MetricsRowPrecedesItsCheckpointAndResumeRewritesIt) {
  testing::TempDir dir;
  const span::ExperimentConfig c = TinyConfig();
  span::TrainRun(c, dir.File("full"), false);
  // The checkpoint of epoch 3 cannot be written (its temporary file is taken by a directory).
  const std::string run = dir.File("failed");
  TrainHooks hooks;
  hooks.continue_after_epoch = [&](int completed) {
    if (completed == 2) std::filesystem::create_directories(run + "/checkpoints/last.pt.tmp");
    return true;
  };
  EXPECT_ANY_THROW(span::TrainRun(c, run, false, hooks));
  EXPECT_EQ(Lines(run + "/metrics.csv").size(), 4u) << "header and the rows of epochs 1-3";
  std::filesystem::remove(run + "/checkpoints/last.pt.tmp");
  const auto resumed = span::TrainRun(c, run, true);  // from the checkpoint of epoch 2
  EXPECT_EQ(resumed.epochs_completed, 4);
  EXPECT_EQ(LossColumns(dir.File("full") + "/metrics.csv"), LossColumns(run + "/metrics.csv"));
}

// Issue 18, defect 4: a full disk during a checkpoint save stops the run with one line and keeps
// the last good checkpoint (LibTorch's file writer used to abort the process).
TEST(Trainer, FullDiskDuringACheckpointKeepsThePreviousOne) {
  testing::TempDir dir;
  const span::ExperimentConfig c = TinyConfig();
  std::unique_ptr<testing::ScopedFileSizeLimit> limit;
  TrainHooks hooks;
  hooks.continue_after_epoch = [&](int completed) {
    if (completed == 2) limit = std::make_unique<testing::ScopedFileSizeLimit>(4096);
    return true;
  };
  testing::ExpectErrorContains([&] { span::TrainRun(c, dir.path(), false, hooks); },
                               {"checkpoints/", "cannot write", "the previous ", ".pt is kept"});
  limit.reset();
  EXPECT_FALSE(std::filesystem::exists(dir.File("checkpoints/last.pt.tmp")));
  EXPECT_FALSE(std::filesystem::exists(dir.File("checkpoints/best.pt.tmp")));
  const auto resumed = span::TrainRun(c, dir.path(), true);  // from the checkpoint of epoch 2
  EXPECT_EQ(resumed.epochs_completed, 4);
}

TEST(Trainer, ResumeRestartsAMissingMetricsFileWithItsHeader) {
  testing::TempDir dir;
  const span::ExperimentConfig c = TinyConfig();
  span::TrainRun(c, dir.path(), false, StopAfter(2));
  const auto header = Lines(dir.File("metrics.csv")).at(0);
  std::filesystem::remove(dir.File("metrics.csv"));
  span::TrainRun(c, dir.path(), true);
  const auto lines = Lines(dir.File("metrics.csv"));
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0], header);
  EXPECT_EQ(lines[1].substr(0, 2), "3,");
  EXPECT_EQ(lines[2].substr(0, 2), "4,");
}

TEST(Trainer, CorruptMetricsIsAClearErrorOnResume) {
  testing::TempDir dir;
  const span::ExperimentConfig c = TinyConfig();
  span::TrainRun(c, dir.path(), false, StopAfter(1));
  testing::WriteText(dir.File("metrics.csv"), "epoch,train_loss\nfirst,1.0\n");
  testing::ExpectErrorContains([&] { span::TrainRun(c, dir.path(), true); },
                               {dir.File("metrics.csv") + ":2", "epoch number"});
}

TEST(Trainer, EmptyValidationSplitIsAClearError) {
  testing::TempDir dir;
  span::ExperimentConfig c = TinyConfig();
  c.data.val_fraction = 0.0;
  testing::ExpectErrorContains([&] { span::TrainRun(c, dir.path(), false); },
                               {"no validation windows", "data.val_fraction"});
}

TEST(Trainer, FreshStartRefusesARunDirectoryThatHoldsARun) {
  testing::TempDir dir;
  span::ExperimentConfig c = TinyConfig();
  c.train.epochs = 1;
  // An attempt that failed before training leaves config.yaml and log.txt: that is no run yet.
  c.data.val_fraction = 0.0;
  EXPECT_THROW(span::TrainRun(c, dir.path(), false), Error);
  c.data.val_fraction = 0.1;
  span::TrainRun(c, dir.path(), false);
  testing::ExpectErrorContains(
      [&] { span::TrainRun(c, dir.path(), false); },
      {dir.path(), "already holds a run (checkpoints/)", "--resume", "--run-dir"});
  for (const char* name : {"model.h5", "eval.json"}) {
    testing::TempDir other;
    testing::WriteText(other.File(name), "x");
    testing::ExpectErrorContains([&] { span::TrainRun(c, other.path(), false); },
                                 {other.path(), std::string("(") + name + ")", "--resume"});
  }
  // A run killed in epoch 1 leaves metrics.csv but no checkpoint: nothing to resume, so a fresh
  // start may replace it.
  testing::TempDir killed;
  testing::WriteText(killed.File("metrics.csv"), "epoch,train_loss\n1,0.5\n");
  EXPECT_NO_THROW(span::TrainRun(c, killed.path(), false));
}

TEST(Trainer, InterruptedBeforeTheFirstCheckpointSuggestsNoResume) {
  testing::TempDir dir;
  const span::ExperimentConfig c = TinyConfig();
  const std::atomic<bool> interrupted{true};
  TrainHooks hooks;
  hooks.interrupt = &interrupted;
  ::testing::internal::CaptureStderr();
  const auto s = span::TrainRun(c, dir.path(), false, hooks);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.reason, TerminationReason::kInterrupted);
  EXPECT_EQ(s.epochs_completed, 0);
  EXPECT_NE(err.find("before the first checkpoint"), std::string::npos) << err;
  EXPECT_EQ(err.find("--resume"), std::string::npos) << err;
  // Nothing was saved, so starting again in the same directory is allowed.
  EXPECT_FALSE(std::filesystem::exists(dir.File("metrics.csv")));
  EXPECT_EQ(span::TrainRun(c, dir.path(), false, StopAfter(1)).epochs_completed, 1);
}

TEST(Trainer, SummaryJsonHasNoInfinityOrNan) {
  TrainingSummary s;
  s.reason = TerminationReason::kNonFiniteLoss;
  s.best_val_loss = INFINITY;  // no epoch completed
  s.last_train_loss = NAN;
  const std::string json = s.ToJson();
  EXPECT_NE(json.find("\"best_val_loss\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"last_train_loss\": null"), std::string::npos) << json;
  EXPECT_EQ(json.find("inf"), std::string::npos) << json;
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
}

void CountingHandler(int) {}

TEST(Trainer, InterruptFlagRestoresThePreviousHandlers) {
  for (auto previous : {&CountingHandler, static_cast<void (*)(int)>(SIG_DFL)}) {
    std::signal(SIGINT, previous);
    std::signal(SIGTERM, previous);
    {
      const ScopedInterruptFlag interrupt;
      EXPECT_FALSE(interrupt.flag()->load());
      std::raise(SIGINT);
      EXPECT_TRUE(interrupt.flag()->load());
    }
    EXPECT_EQ(std::signal(SIGINT, SIG_DFL), previous);
    EXPECT_EQ(std::signal(SIGTERM, SIG_DFL), previous);
  }
}

TEST(Trainer, ResumeRefusesADifferentConfig) {
  testing::TempDir dir;
  span::ExperimentConfig c = TinyConfig();
  c.train.epochs = 1;
  span::TrainRun(c, dir.path(), false);
  c.train.learning_rate = 0.5;
  testing::ExpectErrorContains([&] { span::TrainRun(c, dir.path(), true); },
                               {"config.yaml", "differs"});
}

/// A task whose loss turns NaN in its third epoch.
class ExplodingTask : public TrainingTask {
 public:
  ExplodingTask() : linear_(torch::nn::Linear(2, 1)) {}
  torch::nn::Module& module() override { return *linear_; }
  std::int64_t num_train() const override { return 8; }
  torch::Tensor BatchLoss(const torch::Tensor& idx) override {
    ++calls_;
    auto loss = linear_->forward(torch::ones({idx.size(0), 2})).square().mean();
    return calls_ > 4 ? loss * std::numeric_limits<float>::quiet_NaN()
                      : loss;  // batch 4 of 2 per epoch
  }
  double ValidationLoss() override {
    return linear_->forward(torch::ones({1, 2})).square().item<double>();
  }

 private:
  torch::nn::Linear linear_;
  int calls_ = 0;
};

TEST(Trainer, NonFiniteLossStopsCleanlyAndKeepsTheLastGoodCheckpoint) {
  testing::TempDir dir;
  torch::manual_seed(0);
  ExplodingTask task;
  TrainConfig c;
  c.epochs = 10;
  c.batch_size = 4;
  c.progress = ProgressStyle::kNone;
  const auto s = Train(&task, c, RunPaths{dir.path()}, 0, false);
  EXPECT_EQ(s.reason, TerminationReason::kNonFiniteLoss);
  EXPECT_EQ(s.epochs_completed, 2);
  for (const auto& p : task.module().parameters())
    EXPECT_TRUE(torch::isfinite(p).all().item<bool>());
  // The checkpoint on disk is the epoch-2 one and loads.
  ExplodingTask other;
  LoadCheckpointModel(dir.File("checkpoints/last.pt"), &other.module());
}

TEST(Trainer, CorruptOrMissingCheckpointIsAClearError) {
  testing::TempDir dir;
  span::ExperimentConfig c = TinyConfig();
  c.train.epochs = 1;
  span::TrainRun(c, dir.path(), false);
  const std::string ckpt = dir.File("checkpoints/last.pt");
  testing::Truncate(ckpt, std::filesystem::file_size(ckpt) / 3);
  testing::ExpectErrorContains([&] { span::TrainRun(c, dir.path(), true); },
                               {ckpt, "no checksum trailer (truncated"});
  testing::TempDir empty;
  testing::ExpectErrorContains([&] { span::TrainRun(c, empty.path(), true); },
                               {"no config.yaml to resume from"});
}

// Issue 18, defect 6: a checkpoint with flipped bytes loaded, went non-finite and still exported.
// Its checksum now refuses it before anything is read, for resume and for export alike.
TEST(Trainer, CheckpointWithFlippedBytesIsRefused) {
  testing::TempDir dir;
  span::ExperimentConfig c = TinyConfig();
  c.train.epochs = 1;
  span::TrainRun(c, dir.path(), false);
  for (const char* name : {"checkpoints/last.pt", "checkpoints/best.pt"}) {
    std::string bytes = testing::ReadText(dir.File(name));
    ASSERT_GT(bytes.size(), 1000u);
    bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x5A);
    std::ofstream out(dir.File(name), std::ios::binary | std::ios::trunc);
    out << bytes;
  }
  testing::ExpectErrorContains([&] { span::TrainRun(c, dir.path(), true); },
                               {dir.File("checkpoints/last.pt"), "checksum does not match"});
  testing::ExpectErrorContains([&] { span::ExportRun(dir.path()); },
                               {dir.File("checkpoints/best.pt"), "checksum does not match"});
}

TEST(Trainer, LearningRateSchedules) {
  TrainConfig c;
  c.epochs = 11;
  c.learning_rate = 1.0;
  c.schedule = LrSchedule::kCosine;
  c.min_lr_ratio = 0.1;
  EXPECT_DOUBLE_EQ(LearningRateAt(c, 0), 1.0);
  EXPECT_NEAR(LearningRateAt(c, 5), 0.55, 1e-12);
  EXPECT_NEAR(LearningRateAt(c, 10), 0.1, 1e-12);
  c.schedule = LrSchedule::kStep;
  c.step_every = 3;
  c.step_factor = 0.5;
  EXPECT_DOUBLE_EQ(LearningRateAt(c, 2), 1.0);
  EXPECT_DOUBLE_EQ(LearningRateAt(c, 7), 0.25);
}

}  // namespace
}  // namespace foresight
