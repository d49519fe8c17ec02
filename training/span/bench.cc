// The SPAN kind's bench (`foresight bench RUN_DIR|ARTIFACT`): CPU latency of the Eigen engine
// against LibTorch on the same network, measured side by side in one run (median of many single
// calls, one thread), plus training throughput. A benchmark that prints figures, not a test.

#include "core/bench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>
#include <sstream>

#include "core/error.h"
#include "inference/prediction/span_predictor.h"
#include "models/span/span_net.h"
#include "training/kinds.h"
#include "training/span/torch_io.h"

namespace foresight::span {
namespace {

using bench::Clock;
using bench::Median;

/// Random observed tracks: straight walks with random heading, speed and noise (world, m).
Eigen::MatrixXd RandomPasts(int n, int p, double dt, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd out(n, 2 * p);
  for (int k = 0; k < n; ++k) {
    const double h = M_PI * u(rng), speed = 1.0 + 0.5 * u(rng);
    const Eigen::Vector2d start(10 * u(rng), 10 * u(rng));
    for (int i = 0; i < p; ++i) {
      out(k, 2 * i) = start.x() + i * dt * speed * std::cos(h) + 0.03 * u(rng);
      out(k, 2 * i + 1) = start.y() + i * dt * speed * std::sin(h) + 0.03 * u(rng);
    }
  }
  return out;
}

struct BenchOptions {
  int calls = 20000;  ///< timed single calls of the engine

  template <class A>
  void Serialize(A* a) {
    a->Visit("calls", &calls, config::Range::Closed(100, 10000000),
             "timed single calls of the engine (LibTorch: a quarter, at least 2000)");
  }
};

void RunBench(const BenchRequest& req, const BenchOptions& a) {
  const std::string artifact = BenchArtifact(req, "model.h5");
  const Predictor model = Predictor::Load(artifact);
  const int p = model.observed();
  const Eigen::MatrixXd pasts = RandomPasts(256, p, model.seconds_per_step(), 1);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(p, 2);
  std::vector<double> engine;
  engine.reserve(static_cast<std::size_t>(a.calls));
  for (int i = 0; i < a.calls + 1000; ++i) {
    const int k = i % 256;
    for (int j = 0; j < p; ++j) past(j, 0) = pasts(k, 2 * j), past(j, 1) = pasts(k, 2 * j + 1);
    const auto t0 = Clock::now();
    model.Predict(past, &ws, &dist);
    const auto t1 = Clock::now();
    if (i >= 1000) engine.push_back(bench::Micros(t0, t1));
  }
  const double engine_us = Median(engine);
  // Batch of 1024 through PredictBatch: per-window cost.
  std::vector<TrajectoryDistribution> outs(1024, model.MakeDistribution());
  const Eigen::MatrixXd batch = RandomPasts(1024, p, model.seconds_per_step(), 2);
  std::vector<double> batch_times;
  for (int r = 0; r < 15; ++r) {
    const auto t0 = Clock::now();
    model.PredictBatch(batch, &ws, &outs);
    batch_times.push_back(bench::Micros(t0, Clock::now()));
  }
  const double engine_batch1024_us = Median(batch_times);

  torch::set_num_threads(1);
  LoadedNet loaded = LoadNetFromArtifact(artifact);
  double libtorch_us = NAN, train_windows_per_s = NAN;
  {
    c10::InferenceMode guard;
    const auto x = torch::randn({256, 2 * p});
    std::vector<double> torch_times;
    const int calls = std::max(2000, a.calls / 4);
    for (int i = 0; i < calls + 200; ++i) {
      const auto xi = x.narrow(0, i % 256, 1);
      const auto t0 = Clock::now();
      const auto params = DecodeHead(loaded.net->forward(xi), loaded.layout);
      const auto t1 = Clock::now();
      if (i >= 200) torch_times.push_back(bench::Micros(t0, t1));
      (void)params;
    }
    libtorch_us = Median(torch_times);
  }
  {
    // Training throughput: forward + exact NLL + backward + Adam step on batches of 256.
    const int m = loaded.layout.basis;
    loaded.net->train();
    torch::optim::Adam opt(loaded.net->parameters(), torch::optim::AdamOptions(1e-4));
    const auto x = torch::randn({256, 2 * p});
    const auto w = torch::randn({256, m, 2});
    int steps = 0;
    const auto t0 = Clock::now();
    double elapsed = 0;
    while (elapsed < 1.5 || steps < 10) {
      opt.zero_grad();
      const auto loss =
          MixtureNll(DecodeHead(loaded.net->forward(x), loaded.layout), w, loaded.layout).mean();
      loss.backward();
      opt.step();
      ++steps;
      elapsed = bench::SecondsSince(t0);
    }
    train_windows_per_s = steps * 256.0 / elapsed;
  }
  const double ratio = libtorch_us / engine_us;
  auto num = [](double v) {
    std::ostringstream os;
    if (std::isfinite(v))
      os << v;
    else
      os << "null";
    return os.str();
  };
  if (req.json) {
    std::cout << "{\"artifact\": \"" << artifact
              << "\", \"batch\": 1, \"threads\": 1, \"calls\": " << a.calls
              << ", \"engine_us\": " << num(engine_us) << ", \"libtorch_us\": " << num(libtorch_us)
              << ", \"ratio\": " << num(ratio)
              << ", \"engine_batch1024_us_per_window\": " << num(engine_batch1024_us / 1024.0)
              << ", \"train_windows_per_s\": " << num(train_windows_per_s) << "}\n";
  } else {
    std::printf("engine   (Eigen, batch 1, median of %d calls): %8.2f us\n", a.calls, engine_us);
    std::printf("libtorch (same network + head, batch 1):        %8.2f us\n", libtorch_us);
    std::printf("ratio libtorch / engine:                        %8.1f x\n", ratio);
    std::printf("engine batch 1024 (per window):                 %8.2f us\n",
                engine_batch1024_us / 1024.0);
    std::printf("training throughput (batch 256, 1 thread):      %8.0f windows/s\n",
                train_windows_per_s);
  }
}

}  // namespace

void SetBenchStep(ExperimentKind* kind) { SetBench<BenchOptions>(kind, RunBench); }

}  // namespace foresight::span
