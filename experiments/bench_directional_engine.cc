// Google Benchmark of the directional-map engine (thesis ch 4) at the crossing model's size,
// LibTorch-free: M_s = 36 spatial and M_t = 5 temporal inducing points, R = 5 components, LSTM
// width 40 R = 200 (configs/directional/crossing.yaml). Random weights: latency does not depend on
// their values. The engine-vs-LibTorch ratio of a trained model is `foresight bench RUN_DIR`
// (docs/directional.md); this one times the engine alone, e.g. across compiler flags.
//   build/bin/bench_directional_engine [--benchmark_repetitions=5]

#include <benchmark/benchmark.h>

#include <random>

#include "inference/directional/directional_map.h"

namespace foresight::directional {
namespace {

constexpr int kComponents = 5, kHidden = 40 * kComponents;

Eigen::MatrixXf Random(int rows, int cols, float scale, std::mt19937_64* rng) {
  std::normal_distribution<float> n01;
  return Eigen::MatrixXf::NullaryExpr(rows, cols, [&] { return scale * n01(*rng); });
}

const Map& Model() {
  static const Map map = [] {
    std::mt19937_64 rng(1);
    FeatureConfig f;
    f.cells_x = f.cells_y = 6;
    f.length_scale = 1.5;
    f.time_points = 5;
    f.time_length_scale = 15;
    const int spatial = f.cells_x * f.cells_y;
    const float k = 1.0f / std::sqrt(static_cast<float>(kHidden));
    LstmWeights w;
    w.weight_ih = Random(4 * kHidden, spatial, k, &rng);
    w.weight_hh = Random(4 * kHidden, kHidden, k, &rng);
    w.bias_ih = Random(4 * kHidden, 1, k, &rng);
    w.bias_hh = Random(4 * kHidden, 1, k, &rng);
    Heads h;
    h.alpha_w = Random(kComponents, kHidden, k, &rng);
    h.mu_w = Random(kComponents, kHidden, k, &rng);
    h.kappa_w = Random(kComponents, kHidden, k, &rng);
    h.alpha_b = Random(kComponents, 1, k, &rng);
    h.mu_b = Random(kComponents, 1, k, &rng);
    h.kappa_b = Random(kComponents, 1, k, &rng);
    return Map(Variant::kSpatiotemporal, f, Lstm(std::move(w)), std::move(h));
  }();
  return map;
}

void BM_Query(benchmark::State& state) {
  const Map& m = Model();
  const int n = static_cast<int>(state.range(0));
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u01(0, 1);
  const Eigen::VectorXd x = Eigen::VectorXd::NullaryExpr(n, [&] { return 10 * u01(rng); });
  const Eigen::VectorXd y = Eigen::VectorXd::NullaryExpr(n, [&] { return 10 * u01(rng); });
  const Eigen::VectorXd t = Eigen::VectorXd::NullaryExpr(n, [&] { return 100 * u01(rng); });
  auto ws = m.MakeWorkspace();
  VonMisesMixtureBatch out;
  m.Query(x, y, t, &ws, &out);  // sizes the output once
  for (auto _ : state) {
    m.Query(x, y, t, &ws, &out);
    benchmark::ClobberMemory();
  }
  state.counters["queries/s"] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Query)->Arg(1)->Arg(1024)->Unit(benchmark::kMicrosecond);

// Where a query's time goes: one LSTM step from the zero state (no recurrent product) and one with
// a state (the 4H x H recurrent product); a query runs one of the first and M_t - 1 of the second.
void BM_LstmStep(benchmark::State& state) {
  const Lstm& lstm = Model().lstm();
  auto ws = lstm.MakeWorkspace();
  std::mt19937_64 rng(3);
  const Eigen::VectorXf u = Random(4 * kHidden, 1, 0.3f, &rng);
  const bool with_state = state.range(0) != 0;
  for (auto _ : state) {
    lstm.Reset(&ws);
    if (with_state) lstm.StepProjected(u, 1.0f, &ws);
    lstm.StepProjected(u, 0.5f, &ws);
    benchmark::DoNotOptimize(ws.h.data());
  }
  state.SetLabel(with_state ? "zero-state step + step with state" : "zero-state step");
}
BENCHMARK(BM_LstmStep)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace foresight::directional

BENCHMARK_MAIN();
