// Google Benchmark of the learned GFCS sampler's energy engine: encoding 64 (any k; it only enters
// the per-call context GEMV), energy MLP [21 + k + 7n] -> W -> W -> W -> 1, n = 1 (7 command
// inputs), at the thesis's width W = 800 and the shipped 256 (configs/gfcs/all_families.yaml).
// SGLD at the thesis's 20 and 200 particles x 50 steps, and the shipped sampler's 40 x 30, on
// one thread and on two (SgldParams::threads).
// Random weights: latency does not depend on their values.
//   build/bin/bench_energy_model [--benchmark_repetitions=3]
// Counters: GFLOP/s of the multiply-adds (2 flops each) of the forward and backward GEMMs.

#include <benchmark/benchmark.h>

#include <map>
#include <random>

#include "inference/manipulation/energy_model.h"

namespace foresight::manipulation {
namespace {

constexpr int kEncoding = 64, kCommands = 1;

Mlp RandomMlp(const std::vector<int>& sizes, std::mt19937_64* rng) {
  std::vector<DenseLayer> layers;
  std::normal_distribution<float> n01;
  for (std::size_t i = 0; i + 1 < sizes.size(); ++i) {
    const float scale = 1.0f / std::sqrt(static_cast<float>(sizes[i]));
    DenseLayer l;
    l.weight =
        Eigen::MatrixXf::NullaryExpr(sizes[i + 1], sizes[i], [&] { return scale * n01(*rng); });
    l.bias = Eigen::VectorXf::NullaryExpr(sizes[i + 1], [&] { return 0.1f * n01(*rng); });
    layers.push_back(std::move(l));
  }
  return Mlp(std::move(layers));
}

EnergyModel MakeModel(int width) {
  std::mt19937_64 rng(1);
  EnergyModelParts p;
  p.lattice.lower = Eigen::Vector3d::Zero();
  p.lattice.upper = Eigen::Vector3d::Constant(0.3);
  p.lattice.spacing = 0.3;
  p.bps_mean = Eigen::VectorXf::Zero(8);
  p.bps_std = Eigen::VectorXf::Ones(8);
  p.encoder = RandomMlp({8, kEncoding}, &rng);
  const int in = EnergyModel::kStateContext + kEncoding + 7 * kCommands;
  p.energy = RandomMlp({in, width, width, width, 1}, &rng);
  p.intermediate_commands = kCommands;
  return EnergyModel(std::move(p));
}

/// The model of a width, built once per width.
const EnergyModel& Model(int width) {
  static std::map<int, EnergyModel> models;
  auto it = models.find(width);
  if (it == models.end()) it = models.emplace(width, MakeModel(width)).first;
  return it->second;
}

/// Multiply-adds x 2 of one EnergyAndGradient call over P particles (the context GEMV once).
double Flops(int P, int width, bool with_gradient) {
  const double du = 7 * kCommands, w = width;
  const double forward = P * (w * du + 2 * w * w + w);
  const double backward = with_gradient ? P * (2 * w * w + du * w) : 0;
  return 2 * (forward + backward) + 2 * w * (EnergyModel::kStateContext + kEncoding);
}

Eigen::VectorXf Context(const EnergyModel& m) {
  return Eigen::VectorXf::Constant(m.context_size(), 0.1f);
}

// Args: particles P, width W.
void BM_EnergyAndGradient(benchmark::State& state) {
  const int P = static_cast<int>(state.range(0)), width = static_cast<int>(state.range(1));
  const EnergyModel& m = Model(width);
  auto ws = m.MakeWorkspace(P);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<float> u11(-1, 1);
  const Eigen::MatrixXf u =
      Eigen::MatrixXf::NullaryExpr(m.command_size(), P, [&] { return u11(rng); });
  const Eigen::VectorXf ctx = Context(m);
  Eigen::VectorXf E(P);
  Eigen::MatrixXf G(m.command_size(), P);
  for (auto _ : state) {
    m.EnergyAndGradient(ctx, u, &E, &G, &ws);
    benchmark::DoNotOptimize(E.data());
  }
  state.counters["GFLOP/s"] = benchmark::Counter(Flops(P, width, true) * 1e-9,
                                                 benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_EnergyAndGradient)
    ->ArgNames({"particles", "width"})
    ->Args({20, 800})
    ->Args({200, 800})
    ->Args({40, 256})
    ->Unit(benchmark::kMillisecond);

// Args: particles, steps, width, threads. The shipped sampler is 40 x 30 at width 256. Wall
// time (several threads): SgldParams::threads splits each step's evaluation.
void BM_RunSgld(benchmark::State& state) {
  const int width = static_cast<int>(state.range(2));
  const int threads = static_cast<int>(state.range(3));
  const EnergyModel& m = Model(width);
  SgldParams p;
  p.particles = static_cast<int>(state.range(0));
  p.steps = static_cast<int>(state.range(1));
  std::vector<EnergyModel::Workspace> ws;
  for (int t = 0; t < threads; ++t)
    ws.push_back(m.MakeWorkspace(SgldBlockCapacity(p.particles, threads)));
  const Eigen::VectorXf ctx = Context(m);
  std::mt19937_64 rng(3);
  for (auto _ : state) {
    const SgldResult r =
        threads == 1 ? RunSgld(m, ctx, p, &rng, &ws.front()) : RunSgld(m, ctx, p, &rng, &ws);
    benchmark::DoNotOptimize(r.energy.data());
  }
  // the steps with the gradient plus one final energy-only evaluation
  state.counters["GFLOP/s"] = benchmark::Counter(
      (p.steps * Flops(p.particles, width, true) + Flops(p.particles, width, false)) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_RunSgld)
    ->ArgNames({"particles", "steps", "width", "threads"})
    ->Args({20, 50, 800, 1})
    ->Args({200, 50, 800, 1})
    ->Args({40, 30, 256, 1})
    ->Args({40, 30, 256, 2})
    ->Args({200, 50, 800, 2})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace foresight::manipulation

BENCHMARK_MAIN();
