// The directional kind's bench (`foresight bench RUN_DIR|ARTIFACT`): query latency of the
// directional-map engine (Eigen) against LibTorch on the same exported network, side by side in one
// run, one thread: batch 1 (median of single queries) and batch 1024 (median of repeated batches).
// Both sides go from (x, y, t) to the mixture parameters; the LibTorch side gets the features from
// the same feature code. A benchmark that prints figures, not a test.

#include "core/bench.h"

#include <torch/torch.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <random>

#include "core/error.h"
#include "inference/directional/directional_map.h"
#include "training/directional/pipeline.h"
#include "training/kinds.h"

namespace foresight::directional {
namespace {

using bench::Clock;
using bench::Median;
using RowMatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

double Us(Clock::time_point a, Clock::time_point b) { return bench::Micros(a, b); }

struct BenchOptions {
  int calls = 5000;
  int repeats = 15;

  template <class A>
  void Serialize(A* a) {
    a->Visit("calls", &calls, config::Range::Closed(100, 10000000), "timed single queries");
    a->Visit("repeats", &repeats, config::Range::Closed(1, 10000), "timed batches of 1024");
  }
};

void RunBench(const BenchRequest& req, const BenchOptions& a) {
  torch::set_num_threads(1);
  const std::string artifact = BenchArtifact(req, "model.h5");
  const Map map = Map::Load(artifact);
  const FeatureConfig& fc = map.features().config();
  const int n = 1024;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> ux(fc.x_min, fc.x_max), uy(fc.y_min, fc.y_max),
      ut(fc.t_min, fc.t_max);
  Eigen::VectorXd x(n), y(n), t(n);
  for (int i = 0; i < n; ++i) x[i] = ux(rng), y[i] = uy(rng), t[i] = ut(rng);

  // Engine, batch 1.
  auto ws = map.MakeWorkspace();
  std::vector<double> e1;
  for (int i = 0; i < a.calls + 200; ++i) {
    const int k = i % n;
    const auto t0 = Clock::now();
    map.QueryOne(x[k], y[k], t[k], &ws);
    const auto t1 = Clock::now();
    if (i >= 200) e1.push_back(Us(t0, t1));
  }
  // Engine, batch 1024.
  VonMisesMixtureBatch batch;
  map.Query(x, y, t, &ws, &batch);
  std::vector<double> eb;
  for (int r = 0; r < a.repeats; ++r) {
    const auto t0 = Clock::now();
    map.Query(x, y, t, &ws, &batch);
    eb.push_back(Us(t0, Clock::now()));
  }

  // LibTorch on the same network: features (same code) -> forward -> decode.
  LoadedNet net = LoadNetFromArtifact(artifact);
  const Features& feats = map.features();
  c10::InferenceMode guard;
  auto torch_query = [&](int begin, int len, std::vector<double>* forward_only) {
    const auto t0 = Clock::now();
    RowMatrixF s(len, feats.spatial_size()), tm(len, feats.time_size());
    feats.SpatialBatch(x.segment(begin, len), y.segment(begin, len), s);
    feats.TemporalBatch(t.segment(begin, len), tm);
    const auto ts = torch::from_blob(s.data(), {s.rows(), s.cols()}, torch::kFloat32);
    const auto tt = torch::from_blob(tm.data(), {tm.rows(), tm.cols()}, torch::kFloat32);
    const auto t1 = Clock::now();
    const auto p =
        DecodeVonMisesHead(net.net->forward(ts, tt), net.net->components(), net.net->max_kappa());
    (void)p.kappa.sum().item<float>();
    const auto t2 = Clock::now();
    if (forward_only) forward_only->push_back(Us(t1, t2));
    return Us(t0, t2);
  };
  // The training path: sparse spatial features through an embedding bag.
  std::vector<std::int64_t> index, offsets;
  std::vector<float> value;
  auto torch_sparse = [&](int begin, int len) {
    const auto t0 = Clock::now();
    feats.SpatialSparseBatch(x.segment(begin, len), y.segment(begin, len), &index, &value,
                             &offsets);
    RowMatrixF tm(len, feats.time_size());
    feats.TemporalBatch(t.segment(begin, len), tm);
    const auto nnz = static_cast<std::int64_t>(index.size());
    const auto p = DecodeVonMisesHead(
        net.net->forward_sparse(
            torch::from_blob(index.data(), {nnz}, torch::kInt64),
            torch::from_blob(value.data(), {nnz}, torch::kFloat32),
            torch::from_blob(offsets.data(), {len + 1}, torch::kInt64),
            torch::from_blob(tm.data(), {tm.rows(), tm.cols()}, torch::kFloat32)),
        net.net->components(), net.net->max_kappa());
    (void)p.kappa.sum().item<float>();
    return Us(t0, Clock::now());
  };
  std::vector<double> l1, l1f;
  const int torch_calls = std::max(200, a.calls / 5);
  for (int i = 0; i < torch_calls + 50; ++i) {
    const double us = torch_query(i % n, 1, i >= 50 ? &l1f : nullptr);
    if (i >= 50) l1.push_back(us);
  }
  std::vector<double> lb, lbf;
  torch_query(0, n, nullptr);
  for (int r = 0; r < a.repeats; ++r) lb.push_back(torch_query(0, n, &lbf));
  std::vector<double> s1, sb;
  for (int i = 0; i < torch_calls + 50; ++i) {
    const double us = torch_sparse(i % n, 1);
    if (i >= 50) s1.push_back(us);
  }
  torch_sparse(0, n);
  for (int r = 0; r < a.repeats; ++r) sb.push_back(torch_sparse(0, n));

  const double engine1 = Median(e1), engine_b = Median(eb), torch1 = Median(l1),
               torch_b = Median(lb);
  if (req.json) {
    std::cout << "{\"artifact\": \"" << artifact << "\", \"variant\": \""
              << VariantName(map.variant()) << "\", \"inducing_points\": " << feats.spatial_size()
              << ", \"time_points\": " << feats.time_size()
              << ", \"threads\": 1, \"engine_batch1_us\": " << engine1
              << ", \"libtorch_batch1_us\": " << torch1
              << ", \"libtorch_batch1_forward_us\": " << Median(l1f)
              << ", \"engine_batch1024_us\": " << engine_b
              << ", \"libtorch_batch1024_us\": " << torch_b
              << ", \"libtorch_batch1024_forward_us\": " << Median(lbf)
              << ", \"libtorch_sparse_batch1_us\": " << Median(s1)
              << ", \"libtorch_sparse_batch1024_us\": " << Median(sb) << "}\n";
    return;
  }
  std::printf("directional map %s: %d x %d inducing points x %d times, R = %d, 1 thread\n",
              VariantName(map.variant()), fc.cells_x, fc.cells_y, fc.time_points, map.components());
  std::printf("batch 1    engine (median of %d):   %10.2f us\n", a.calls, engine1);
  std::printf(
      "batch 1    libtorch (features+net):  %10.2f us   (net only %.2f us)   ratio %.1f x\n",
      torch1, Median(l1f), torch1 / engine1);
  std::printf("batch 1024 engine (median of %d):     %10.1f us   (%.2f us/query)\n", a.repeats,
              engine_b, engine_b / n);
  std::printf(
      "batch 1024 libtorch (features+net):  %10.1f us   (net only %.1f us)   ratio %.2f x\n",
      torch_b, Median(lbf), torch_b / engine_b);
  std::printf(
      "libtorch, sparse features (embedding bag, the training path): batch 1 %.2f us (ratio %.1f "
      "x), "
      "batch 1024 %.1f us (ratio %.2f x)\n",
      Median(s1), Median(s1) / engine1, Median(sb), Median(sb) / engine_b);
}

}  // namespace

void SetBenchStep(ExperimentKind* kind) { SetBench<BenchOptions>(kind, RunBench); }

}  // namespace foresight::directional
