// The OTNet kind's bench (`foresight bench RUN_DIR|ARTIFACT`): the time OTNet
// (thesis ch 6) takes to turn a new map into collision-checked trajectories from a start point,
// stage by stage, on one thread (medians of repeated runs): the Hausdorff encoding, the network
// (the torch-free engine vs LibTorch on the same weights), start conditioning + sampling and
// collision checking. A benchmark that prints figures, not a test.

#include "core/bench.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "inference/otnet/otnet_model.h"
#include "models/otnet/otnet_net.h"
#include "training/kinds.h"

namespace foresight::otnet {

namespace {

using bench::Clock;
using bench::Median;

struct OtnetBenchOptions {
  int repeats = 7;
  int count = 100;

  template <class A>
  void Serialize(A* a) {
    a->Visit("repeats", &repeats, config::Range::Closed(1, 100), "timed runs (median reported)");
    a->Visit("count", &count, config::Range::Closed(1, 10000), "trajectories to generate");
  }
};

/// Median over `repeats` of the mean time (us) of one call of f; each timed run makes enough
/// calls to last about a millisecond (one call for slow stages), after a warm-up call.
template <class F>
double MicrosPerCall(int repeats, F&& f) {
  f();
  const auto s = Clock::now();
  f();
  const double once = bench::Micros(s, Clock::now());
  const int calls =
      static_cast<int>(std::clamp(std::ceil(1000.0 / std::max(once, 1e-3)), 1.0, 1e5));
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto start = Clock::now();
    for (int i = 0; i < calls; ++i) f();
    t.push_back(bench::Micros(start, Clock::now()) / calls);
  }
  return Median(t);
}

/// Database map 0 with a few free cells next to walls made occupied (spread evenly over the
/// candidates, deterministic): a map the database does not hold, still with walls and free space.
BinaryGrid QueryMap(const MapEncoder& encoder) {
  BinaryGrid map = encoder.database().front();
  std::vector<std::pair<int, int>> candidates;
  for (int r = 1; r + 1 < map.height; ++r)
    for (int c = 1; c + 1 < map.width; ++c)
      if (map.at(r, c) == 0 &&
          (map.at(r - 1, c) || map.at(r + 1, c) || map.at(r, c - 1) || map.at(r, c + 1)))
        candidates.emplace_back(r, c);
  FS_THROW_UNLESS(candidates.size() >= 16, "bench: database map 0 has only ", candidates.size(),
                  " free interior cells next to a wall (16 needed to perturb it)");
  constexpr int kFlips = 6;
  for (int i = 1; i <= kFlips; ++i) {
    const auto [r, c] = candidates[i * candidates.size() / (kFlips + 1)];
    map.at(r, c) = 1;
  }
  return map;
}

/// The alpha-weighted mean start (tau = 0) of the predicted mixture, moved to the nearest free cell
/// centre of `map`.
Eigen::Vector2d StartPoint(const OtnetModel& model, const Mixture& mixture, const BinaryGrid& map) {
  const Eigen::VectorXd tau0 = Eigen::VectorXd::Zero(1);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int q = 0; q < mixture.components(); ++q) {
    Eigen::MatrixX2d m;
    Eigen::MatrixXd cx, cy;
    model.ComponentMarginals(mixture, q, tau0, &m, &cx, &cy);
    mean += mixture.alpha[q] * m.row(0).transpose();
  }
  Eigen::Vector2d best(-1, -1);
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c) {
      if (map.at(r, c)) continue;
      const Eigen::Vector2d centre(c + 0.5, r + 0.5);
      const double d2 = (centre - mean).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best = centre;
      }
    }
  FS_THROW_UNLESS(std::isfinite(best_d2), "bench: the query map has no free cell");
  return best;
}

/// The LibTorch net holding the engine MLP's weights (already on raw phi, so the normalisation
/// is the identity).
OtnetNet TorchNet(const OtnetModel& model) {
  const std::vector<DenseLayer>& layers = model.mlp().layers();
  OtnetNetOptions o;
  o.inputs = model.mlp().input_size();
  o.hidden.clear();
  for (std::size_t i = 0; i + 1 < layers.size(); ++i)
    o.hidden.push_back(static_cast<int>(layers[i].weight.rows()));
  o.components = model.components();
  o.weights = model.basis().weights();
  o.family = model.family();
  OtnetNet net(o);
  torch::NoGradGuard no_grad;
  const std::vector<torch::nn::Linear> linears = net->linears();
  for (std::size_t i = 0; i < layers.size(); ++i) {
    using RowMajorF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    RowMajorF w = layers[i].weight;
    Eigen::VectorXf b = layers[i].bias;
    linears[i]->weight.copy_(torch::from_blob(w.data(), {w.rows(), w.cols()}, torch::kFloat32));
    linears[i]->bias.copy_(torch::from_blob(b.data(), {b.size()}, torch::kFloat32));
  }
  net->eval();
  return net;
}

struct TorchMixture {
  torch::Tensor alpha, mean, scale;
};

/// What PredictFromFeatures computes, in LibTorch: forward, then softmax and exp of the head.
TorchMixture TorchPredict(OtnetNet& net, const torch::Tensor& phi) {
  const MixtureOutputs out = net->Split(net->forward(phi));
  return {torch::softmax(out.logits, 1), out.mean, torch::exp(out.log_scale)};
}

/// Largest |engine - LibTorch| relative to (1 + |engine|) over alpha, means and scales.
double Disagreement(const Mixture& m, const TorchMixture& t) {
  const torch::Tensor alpha = t.alpha.to(torch::kFloat64).contiguous();
  const torch::Tensor mean = t.mean.to(torch::kFloat64).contiguous();
  const torch::Tensor scale = t.scale.to(torch::kFloat64).contiguous();
  const double* a = alpha.data_ptr<double>();
  const double* mu = mean.data_ptr<double>();
  const double* s = scale.data_ptr<double>();
  double worst = 0;
  const auto see = [&worst](double engine, double torch_value) {
    worst = std::max(worst, std::abs(engine - torch_value) / (1 + std::abs(engine)));
  };
  const int n = static_cast<int>(m.mean.cols());
  for (int q = 0; q < m.components(); ++q) {
    see(m.alpha[q], a[q]);
    for (int j = 0; j < n; ++j) {
      see(m.mean(q, j), mu[q * n + j]);
      see(m.scale(q, j), s[q * n + j]);
    }
  }
  return worst;
}

void RunOtnetBench(const BenchRequest& req, const OtnetBenchOptions& a) {
  torch::set_num_threads(1);
  const std::string artifact = BenchArtifact(req, "model.h5");
  const OtnetModel model = OtnetModel::Load(artifact);
  const MapEncoder& encoder = model.encoder();
  const BinaryGrid map = QueryMap(encoder);
  constexpr int kPoints = 100;
  OtnetModel::Workspace ws = model.MakeWorkspace(a.count, kPoints);
  MapEncoder::Workspace ew = encoder.MakeWorkspace();
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(encoder.size());
  Mixture mixture;

  const double encode = MicrosPerCall(a.repeats, [&] { encoder.Encode(map, &ew, phi); });
  const double engine =
      MicrosPerCall(a.repeats, [&] { model.PredictFromFeatures(phi, &ws, &mixture); });

  OtnetNet net = TorchNet(model);
  torch::NoGradGuard no_grad;
  Eigen::VectorXf phi_f = phi.cast<float>();
  const torch::Tensor x = torch::from_blob(phi_f.data(), {1, phi_f.size()}, torch::kFloat32);
  TorchMixture torch_mixture;
  const double libtorch = MicrosPerCall(a.repeats, [&] { torch_mixture = TorchPredict(net, x); });
  const double disagreement = Disagreement(mixture, torch_mixture);
  FS_THROW_UNLESS(disagreement < 1e-3,
                  "bench: the LibTorch copy of the network disagrees "
                  "with the engine by ",
                  disagreement, " (relative)");

  const Eigen::Vector2d start = StartPoint(model, mixture, map);
  GenerateOptions go;
  go.count = a.count;
  go.points = kPoints;
  go.max_attempts = std::max(2000, 20 * a.count);
  GenerateStats stats;
  const double generate = MicrosPerCall(a.repeats, [&] {
    std::mt19937_64 rng(1);  // the same samples every call
    model.ConditionOnStart(mixture, start, ComponentSelection::kNearest, &ws.conditioned);
    stats = model.Generate(map, ws.conditioned, go, &rng, &ws);
  });
  const double total = encode + engine + generate;
  const double ratio = libtorch / engine;

  if (req.json) {
    std::cout << "{\"encode_us\": " << encode << ", \"network_engine_us\": " << engine
              << ", \"network_libtorch_us\": " << libtorch
              << ", \"libtorch_over_engine\": " << ratio << ", \"generate_us\": " << generate
              << ", \"total_us\": " << total << ", \"accepted\": " << stats.accepted
              << ", \"rejected\": " << stats.rejected << ", \"attempts\": " << stats.attempts
              << ", \"repeats\": " << a.repeats << ", \"database_size\": " << encoder.size()
              << ", \"components\": " << model.components()
              << ", \"basis\": " << model.basis().size() << "}\n";
    return;
  }
  std::cout << "OTNet on a perturbed database map 0 (" << map.width << "x" << map.height << "), "
            << encoder.size() << " database maps, Q = " << model.components()
            << ", M = " << model.basis().size() << ", " << ToString(model.family())
            << "; one thread, median of " << a.repeats << " runs:\n"
            << "  encode (Hausdorff similarities):        " << encode << " us\n"
            << "  network, engine:                        " << engine << " us\n"
            << "  network, LibTorch (batch 1, no grad):   " << libtorch << " us  (" << ratio
            << "x the engine; outputs agree to " << disagreement << ")\n"
            << "  condition (nearest) + generate " << a.count << ":      " << generate << " us  ("
            << stats.accepted << " accepted, " << stats.rejected << " rejected, " << stats.attempts
            << " drawn; start (" << start.x() << ", " << start.y() << "))\n"
            << "  total (encode + engine + generate):     " << total << " us\n";
}

}  // namespace

void SetBenchStep(ExperimentKind* kind) { SetBench<OtnetBenchOptions>(kind, RunOtnetBench); }

}  // namespace foresight::otnet
