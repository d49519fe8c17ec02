// Google Benchmark fixtures of the SPAN engine's hot paths on a thesis-sized network (3 x 100 ReLU,
// m = 8, R = 1 and R = 3). Random weights: latency does not depend on their values.
//   build/bin/bench_span_engine [--benchmark_repetitions=5]

#include <benchmark/benchmark.h>

#include <filesystem>

#include "inference/prediction/span_predictor.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

const span::Predictor& Model(int components) {
  static std::map<int, span::Predictor> models;
  auto it = models.find(components);
  if (it == models.end()) {
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("bench_span_R" + std::to_string(components) + ".h5"))
                                 .string();
    testing::RandomSpanSpec spec;
    spec.basis = 8;
    spec.components = components;
    spec.hidden = {100, 100, 100};
    spec.u_param = components == 1 ? UParam::kCholesky : UParam::kDiagonal;
    testing::WriteRandomSpanArtifact(path, spec);
    it = models.emplace(components, span::Predictor::Load(path)).first;
  }
  return it->second;
}

Eigen::Matrix<double, Eigen::Dynamic, 2> Past(int p) {
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(p, 2);
  for (int i = 0; i < p; ++i) past.row(i) << 0.5 * i, 0.1 * i;
  return past;
}

void BM_Predict(benchmark::State& state) {
  const span::Predictor& model = Model(static_cast<int>(state.range(0)));
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  const auto past = Past(model.observed());
  for (auto _ : state) {
    model.Predict(past, &ws, &dist);
    benchmark::DoNotOptimize(dist.alpha(0));
  }
}
BENCHMARK(BM_Predict)->Arg(1)->Arg(3);

void BM_PositionQuery(benchmark::State& state) {
  const span::Predictor& model = Model(1);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  model.Predict(Past(model.observed()), &ws, &dist);
  Eigen::Vector2d mu;
  Eigen::Matrix2d cov;
  double t = 0;
  for (auto _ : state) {
    t = t > 4.0 ? 0.0 : t + 0.1;
    dist.Position(t, 0, &mu, &cov);
    benchmark::DoNotOptimize(cov(0, 0));
  }
}
BENCHMARK(BM_PositionQuery);

void BM_SamplePath40(benchmark::State& state) {
  const span::Predictor& model = Model(1);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  model.Predict(Past(model.observed()), &ws, &dist);
  const Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(40, 0.1, 4.0);
  Eigen::Matrix<double, Eigen::Dynamic, 2> path(40, 2);
  std::mt19937_64 rng(1);
  for (auto _ : state) {
    dist.SamplePath(times, &rng, path);
    benchmark::DoNotOptimize(path(39, 0));
  }
}
BENCHMARK(BM_SamplePath40);

}  // namespace
}  // namespace foresight

BENCHMARK_MAIN();
