/// Data-parallel training speed: the per-step time of the trainer (Train(), Adam, gradient
/// clipping) on one MLP regression task with one rank against several ranks (c10d Gloo, a
/// FileStore in a temporary directory), each rank with its own process. A step is the time
/// between two consecutive BatchLoss calls of rank 0: forward and backward on its slice of the
/// global batch, the gradient all-reduce, clipping and the Adam update. Medians of repeats.
///
///   bench_distributed [--batch 512] [--hidden 800] [--layers 3] [--steps 30] [--repeats 5]
///
/// Not part of ctest (timings depend on the machine); docs/distributed.md quotes its output.

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "training/distributed.h"
#include "training/trainer.h"

extern char** environ;

namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct Options {
  int batch = 512, hidden = 800, layers = 3, input = 64, steps = 30, repeats = 5, ranks = 2;
};

/// Regression with an MLP (input -> hidden x layers, ReLU -> 1); records when each batch starts.
class MlpTask : public foresight::TrainingTask {
 public:
  MlpTask(const Options& o, std::int64_t n) {
    torch::manual_seed(1);
    x_ = torch::randn({n, o.input});
    y_ = torch::sin(x_.sum(1, true));
    x_val_ = torch::randn({256, o.input});
    y_val_ = torch::sin(x_val_.sum(1, true));
    net_ = torch::nn::Sequential();
    int width = o.input;
    for (int l = 0; l < o.layers; ++l) {
      net_->push_back(torch::nn::Linear(width, o.hidden));
      net_->push_back(torch::nn::ReLU());
      width = o.hidden;
    }
    net_->push_back(torch::nn::Linear(width, 1));
  }
  torch::nn::Module& module() override { return *net_; }
  std::int64_t num_train() const override { return x_.size(0); }
  torch::Tensor BatchLoss(const torch::Tensor& idx) override {
    starts.push_back(Clock::now());
    return torch::mse_loss(net_->forward(x_.index_select(0, idx)), y_.index_select(0, idx));
  }
  double ValidationLoss() override {
    return torch::mse_loss(net_->forward(x_val_), y_val_).item<double>();
  }
  std::vector<Clock::time_point> starts;

 private:
  torch::Tensor x_, y_, x_val_, y_val_;
  torch::nn::Sequential net_{nullptr};
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// One rank: `repeats` one-epoch runs of `steps` + 1 steps; rank 0 writes the median step time
/// (ms) of each repeat to FORESIGHT_BENCH_OUT, one per line.
int Worker(const Options& o, int threads) {
  auto group = foresight::dist::DefaultGroup();
  MlpTask task(o, static_cast<std::int64_t>(o.batch) * (o.steps + 1));
  foresight::TrainConfig c;
  c.epochs = 1;
  c.batch_size = o.batch;
  c.patience = 0;
  c.threads = threads;
  c.progress = foresight::ProgressStyle::kNone;
  const std::string out = std::getenv("FORESIGHT_BENCH_OUT");
  std::ostringstream lines;
  for (int r = 0; r < o.repeats; ++r) {
    task.starts.clear();
    foresight::Train(&task, c, foresight::RunPaths{out + ".run"}, 1, false);
    std::vector<double> ms;  // the first step (warm-up) is not counted
    for (std::size_t i = 2; i < task.starts.size(); ++i)
      ms.push_back(
          std::chrono::duration<double, std::milli>(task.starts[i] - task.starts[i - 1]).count());
    lines << Median(ms) << "\n";
  }
  if (group->rank() == 0) std::ofstream(out) << lines.str();
  return 0;
}

/// Runs `ranks` worker processes with `threads` intra-op threads each; the per-repeat medians.
std::vector<double> Measure(const Options& o, int ranks, int threads, const fs::path& tmp) {
  const std::string tag = std::to_string(ranks) + "x" + std::to_string(threads);
  const std::string out = (tmp / ("out_" + tag)).string();
  std::vector<pid_t> pids;
  for (int rank = 0; rank < ranks; ++rank) {
    std::vector<std::string> env;
    for (char** e = environ; *e; ++e) env.push_back(*e);
    env.push_back("RANK=" + std::to_string(rank));
    env.push_back("WORLD_SIZE=" + std::to_string(ranks));
    env.push_back("FORESIGHT_STORE_FILE=" + (tmp / ("store_" + tag)).string());
    env.push_back("FORESIGHT_BENCH_OUT=" + out);
    std::vector<std::string> args{"/proc/self/exe", "--worker",
                                  "--threads",      std::to_string(threads),
                                  "--batch",        std::to_string(o.batch),
                                  "--hidden",       std::to_string(o.hidden),
                                  "--layers",       std::to_string(o.layers),
                                  "--steps",        std::to_string(o.steps),
                                  "--repeats",      std::to_string(o.repeats)};
    std::vector<char*> argv, envp;
    for (auto& s : args) argv.push_back(s.data());
    for (auto& s : env) envp.push_back(s.data());
    argv.push_back(nullptr);
    envp.push_back(nullptr);
    pid_t pid = 0;
    if (::posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, argv.data(), envp.data()) != 0)
      foresight::Fail("cannot start a worker process");
    pids.push_back(pid);
  }
  for (pid_t pid : pids) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    FS_THROW_UNLESS(WIFEXITED(status) && WEXITSTATUS(status) == 0, "a worker of ", tag, " failed");
  }
  std::ifstream in(out);
  std::vector<double> ms;
  for (double v; in >> v;) ms.push_back(v);
  FS_THROW_UNLESS(static_cast<int>(ms.size()) == o.repeats, out, ": missing timings");
  return ms;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  bool worker = false;
  int threads = 1;
  CLI::App app{"data-parallel training step time: 1 rank vs several (c10d Gloo)"};
  app.add_option("--batch", o.batch, "global batch size");
  app.add_option("--hidden", o.hidden, "MLP width");
  app.add_option("--layers", o.layers, "hidden layers");
  app.add_option("--steps", o.steps, "timed steps per repeat");
  app.add_option("--repeats", o.repeats, "repeats (one process start each configuration)");
  app.add_option("--ranks", o.ranks, "ranks of the data-parallel run");
  app.add_option("--threads", threads, "intra-op threads (worker)")->group("");
  app.add_flag("--worker", worker, "run as one rank (internal)")->group("");
  CLI11_PARSE(app, argc, argv);
  try {
    if (worker) return Worker(o, threads);
    const fs::path tmp =
        fs::temp_directory_path() / ("foresight_bench_distributed_" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    const long long params =
        static_cast<long long>(o.input) * o.hidden + o.hidden +
        static_cast<long long>(o.layers - 1) * (o.hidden * o.hidden + o.hidden) + o.hidden + 1;
    std::cout << "MLP " << o.input << " -> " << o.layers << "x" << o.hidden << " ReLU -> 1 ("
              << params << " parameters), global batch " << o.batch << ", " << o.steps
              << " steps x " << o.repeats << " repeats, " << std::thread::hardware_concurrency()
              << " cores\n";
    std::printf("%-22s %14s %12s   %s\n", "configuration", "step [ms]", "samples/s",
                "per-repeat medians [ms]");
    double one = 0, many = 0;
    for (const auto& [ranks, t] :
         std::vector<std::pair<int, int>>{{1, 1}, {o.ranks, 1}, {1, o.ranks}}) {
      const auto ms = Measure(o, ranks, t, tmp);
      const double med = Median(ms);
      if (ranks == 1 && t == 1) one = med;
      if (ranks == o.ranks && t == 1) many = med;
      std::ostringstream each;
      for (double v : ms) each << " " << std::round(v * 100) / 100;
      const std::string name = std::to_string(ranks) + " rank" + (ranks > 1 ? "s" : "") + " x " +
                               std::to_string(t) + " thread" + (t > 1 ? "s" : "");
      std::printf("%-22s %14.2f %12.0f  %s\n", name.c_str(), med, o.batch / (med / 1000.0),
                  each.str().c_str());
    }
    std::printf("speed-up of %d ranks x 1 thread over 1 rank x 1 thread: %.2fx\n", o.ranks,
                one / many);
    fs::remove_all(tmp);
  } catch (const foresight::Error& e) {
    std::cerr << "bench_distributed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
