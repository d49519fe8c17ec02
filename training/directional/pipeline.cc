#include "training/directional/pipeline.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numeric>
#include <random>
#include <sstream>

#include "core/error.h"
#include "core/file_io.h"
#include "core/h5.h"
#include "core/log.h"
#include "core/von_mises.h"
#include "datasets/data_root.h"
#include "inference/engine/artifact.h"
#include "models/directional/directional_grid_map.h"
#include "models/directional/knn_directional.h"
#include "training/directional/plots.h"
#include "training/run_dir.h"
#include "training/tensor_eigen.h"

namespace foresight::directional {
namespace fs = std::filesystem;

namespace {

/// The networks a config trains: spatiotemporal and/or spatial.
std::vector<Variant> TrainedVariants(const ExperimentConfig& c) {
  std::vector<Variant> variants;
  if (c.eval.spatiotemporal) variants.push_back(Variant::kSpatiotemporal);
  if (c.eval.spatial) variants.push_back(Variant::kSpatial);
  return variants;
}

/// How many of the K folds a run evaluates (eval.max_folds, 0: all).
int EvaluatedFolds(const ExperimentConfig& c) {
  return c.eval.max_folds > 0 ? c.eval.max_folds : c.eval.folds;
}

using RowMatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

std::vector<Eigen::Index> RandomSubset(Eigen::Index n, double fraction, std::uint64_t seed) {
  std::vector<Eigen::Index> idx(static_cast<std::size_t>(n));
  std::iota(idx.begin(), idx.end(), Eigen::Index{0});
  std::mt19937_64 rng(seed);
  std::shuffle(idx.begin(), idx.end(), rng);
  const auto keep = std::max<Eigen::Index>(
      1, static_cast<Eigen::Index>(std::llround(fraction * static_cast<double>(n))));
  idx.resize(static_cast<std::size_t>(std::min(keep, n)));
  std::sort(idx.begin(), idx.end());
  return idx;
}

torch::Tensor ToTensor(const Eigen::VectorXd& v) {
  Eigen::VectorXf f = v.cast<float>();
  return torch::from_blob(f.data(), {f.size()}, torch::kFloat32).clone();
}

/// Features are computed per batch from the positions (memory stays O(n), not O(n M_s)).
class DirectionalTask : public TrainingTask {
 public:
  DirectionalTask(Net net, Features features, const DirectionalSamples& train,
                  const DirectionalSamples& val, const Penalty& penalty)
      : net_(std::move(net)),
        features_(std::move(features)),
        train_(train),
        val_(val),
        penalty_(penalty),
        theta_train_(ToTensor(train.theta)),
        theta_val_(ToTensor(val.theta)) {}

  torch::nn::Module& module() override { return *net_; }
  std::int64_t num_train() const override { return train_.size(); }

  torch::Tensor BatchLoss(const torch::Tensor& indices) override {
    const auto idx = indices.to(torch::kInt64).contiguous();
    const std::int64_t b = idx.size(0);
    const auto* p = idx.data_ptr<std::int64_t>();
    Eigen::VectorXd x(b), y(b), t(b);
    for (std::int64_t i = 0; i < b; ++i)
      x[i] = train_.x[p[i]], y[i] = train_.y[p[i]], t[i] = train_.t[p[i]];
    return LossFromRaw(*net_, Forward(x, y, t), theta_train_.index_select(0, idx), penalty_);
  }

  double ValidationLoss() override {
    torch::NoGradGuard no_grad;
    const Eigen::Index n = val_.size();
    FS_THROW_UNLESS(n > 0, "no validation samples to compute the validation loss on");
    double sum = 0;
    for (Eigen::Index b = 0; b < n; b += 512) {
      const Eigen::Index len = std::min<Eigen::Index>(512, n - b);
      const auto raw =
          Forward(val_.x.segment(b, len), val_.y.segment(b, len), val_.t.segment(b, len));
      sum += VonMisesMixtureNll(DecodeVonMisesHead(raw, net_->components(), net_->max_kappa()),
                                theta_val_.narrow(0, b, len))
                 .sum()
                 .item<double>();
    }
    return sum / static_cast<double>(n);
  }

 private:
  /// Raw outputs from sparse spatial features (embedding bag) and dense temporal ones.
  torch::Tensor Forward(const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                        const Eigen::VectorXd& t) {
    features_.SpatialSparseBatch(x, y, &index_, &value_, &offsets_);
    RowMatrixF tm(t.size(), features_.time_size());
    features_.TemporalBatch(t, tm);
    const auto n = static_cast<std::int64_t>(index_.size());
    const auto ti = torch::from_blob(index_.data(), {n}, torch::kInt64).clone();
    const auto tv = torch::from_blob(value_.data(), {n}, torch::kFloat32).clone();
    const auto to = torch::from_blob(offsets_.data(), {static_cast<std::int64_t>(offsets_.size())},
                                     torch::kInt64)
                        .clone();
    const auto tt = torch::from_blob(tm.data(), {tm.rows(), tm.cols()}, torch::kFloat32).clone();
    return net_->forward_sparse(ti, tv, to, tt);
  }

  Net net_;
  Features features_;
  std::vector<std::int64_t> index_, offsets_;
  std::vector<float> value_;
  const DirectionalSamples& train_;
  const DirectionalSamples& val_;
  Penalty penalty_;
  torch::Tensor theta_train_, theta_val_;
};

Penalty PenaltyOf(const NetworkConfig& n) { return {n.lambda_alpha, n.lambda_mu, n.lambda_kappa}; }

Net MakeNet(const ExperimentConfig& c, const FeatureConfig& f, Variant v) {
  return Net(v, f.cells_x * f.cells_y, c.network.components, c.network.Hidden(),
             c.network.max_kappa);
}

/// Splits `samples` into (train, val) with a seeded val_fraction (both non-empty).
std::pair<DirectionalSamples, DirectionalSamples> SplitVal(const DirectionalSamples& s,
                                                           double val_fraction,
                                                           std::uint64_t seed) {
  FS_THROW_UNLESS(s.size() >= 2, "directional: ", s.size(),
                  " training samples; need at least 2 (one to train, one to validate)");
  std::vector<Eigen::Index> idx(static_cast<std::size_t>(s.size()));
  std::iota(idx.begin(), idx.end(), Eigen::Index{0});
  std::mt19937_64 rng(seed);
  std::shuffle(idx.begin(), idx.end(), rng);
  auto nv = static_cast<std::size_t>(std::llround(val_fraction * static_cast<double>(s.size())));
  nv = std::clamp<std::size_t>(nv, 1, idx.size() - 1);
  std::vector<Eigen::Index> val(idx.begin(), idx.begin() + static_cast<long>(nv));
  std::vector<Eigen::Index> train(idx.begin() + static_cast<long>(nv), idx.end());
  std::sort(val.begin(), val.end());
  std::sort(train.begin(), train.end());
  return {s.Select(train), s.Select(val)};
}

std::vector<Eigen::Index> Complement(Eigen::Index n, const std::vector<Eigen::Index>& test) {
  std::vector<char> in(static_cast<std::size_t>(n), 0);
  for (auto i : test) in[static_cast<std::size_t>(i)] = 1;
  std::vector<Eigen::Index> out;
  for (Eigen::Index i = 0; i < n; ++i)
    if (!in[static_cast<std::size_t>(i)]) out.push_back(i);
  return out;
}

std::string Num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os << std::setprecision(6) << v;
  return os.str();
}

double Mean(const std::vector<double>& v) {
  if (v.empty()) return NAN;
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}
double Std(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = Mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

GridConfig GridConfigOf(const ExperimentConfig& c, const FeatureConfig& f, GridKind kind,
                        bool dense) {
  GridConfig g;
  g.kind = kind;
  g.cells_x = f.cells_x;
  g.cells_y = f.cells_y;
  g.extent = Eigen::Vector4d(f.x_min, f.x_max, f.y_min, f.y_max);
  g.components = c.eval.grid_components;
  g.dense = dense;
  const double spacing = 0.5 * ((f.x_max - f.x_min) / f.cells_x + (f.y_max - f.y_min) / f.cells_y);
  g.length_scale = c.eval.grid_length_scale > 0 ? c.eval.grid_length_scale : spacing;
  g.seed = static_cast<std::uint64_t>(c.seed);
  g.max_kappa = c.network.max_kappa;  // one cap for every method
  return g;
}

Score ScoreOf(const EvalConfig& e, const VonMisesMixtureBatch& b, const Eigen::VectorXd& theta) {
  Score s;
  s.al = AverageLikelihood(b, theta);
  s.mre = MinimumRotationError(b, theta);
  s.mre_w = MinimumRotationError(b, theta, e.mre_min_weight);
  for (const double cap : e.metric_caps) {
    VonMisesMixtureBatch capped = b;
    CapConcentration(&capped, cap);
    s.al_caps.push_back(AverageLikelihood(capped, theta));
  }
  return s;
}

/// "10" for 10, "2.5" for 2.5: the suffix of al_cap<c>.
std::string CapName(double cap) {
  std::ostringstream os;
  os << cap;
  return os.str();
}

}  // namespace

// ---------------------------------------------------------------------------------------------

DirectionalSamples LoadSamples(const ExperimentConfig& c) {
  DirectionalSamples s;
  DirectionalReadStats stats;
  std::string where;
  switch (c.data.format) {
    case Source::kCrossing: {
      CrossingFlowConfig flow = c.data.crossing.flow;
      flow.seed = static_cast<std::uint64_t>(c.seed);
      s = GenerateCrossingFlow(flow);
      where = "synthetic crossing";
      break;
    }
    case Source::kGridCsv:
      where = ResolveDataFile(c.data.root, c.data.file);
      s = ReadDirectionalGridCsv(where, &stats);
      break;
    case Source::kEdinburgh:
      where = ResolveDataFile(c.data.root, c.data.file);
      s = ReadEdinburghTracks(where, c.data.edinburgh.filter, &stats);
      break;
  }
  if (c.data.format != Source::kCrossing)
    log::Info(where, ": ", stats.points, " points in ", stats.tracks, " tracks, kept ", stats.kept,
              " headings; dropped standing ", stats.dropped_standing, ", jumps ",
              stats.dropped_jump, ", gaps ", stats.dropped_gap, ", short tracks ",
              stats.dropped_short_track);
  s.Validate(where);
  if (c.data.max_samples > 0 && s.size() > c.data.max_samples) {
    s = s.Select(RandomSubset(
        s.size(), static_cast<double>(c.data.max_samples) / static_cast<double>(s.size()),
        static_cast<std::uint64_t>(c.seed) + 101));
    log::Info("subsampled to ", s.size(), " samples (data.max_samples)");
  }
  return s;
}

void WriteArtifact(NetImpl& net, const FeatureConfig& fc, const std::string& config_yaml,
                   std::int64_t seed, const std::string& path) {
  FS_THROW_UNLESS(!fc.auto_extent && !fc.auto_time_range,
                  "WriteDirectionalArtifact: unresolved feature extent");
  const auto params = net.named_parameters();
  auto matrix = [&](const std::string& name) { return ToEigenMatrix(params[name]); };
  auto vector = [&](const std::string& name) { return ToEigenVector(params[name]); };
  Lstm lstm;
  if (net.variant() == Variant::kSpatiotemporal)
    lstm = Lstm(LstmWeights{matrix("lstm.weight_ih_l0"), matrix("lstm.weight_hh_l0"),
                            vector("lstm.bias_ih_l0"), vector("lstm.bias_hh_l0")});
  Heads heads{matrix("alpha.weight"), matrix("mu.weight"), matrix("kappa.weight"),
              vector("alpha.bias"),   vector("mu.bias"),   vector("kappa.bias")};
  Map(net.variant(), fc, std::move(lstm), std::move(heads), net.max_kappa())
      .Save(path, config_yaml, seed);
}

LoadedNet LoadNetFromArtifact(const std::string& path) {
  const Artifact art = Artifact::Open(path, kModelType);
  const h5::File& f = art.file();
  // The engine loader checks every shape; reuse it for the feature config and the variant.
  const Map map = Map::Load(path);
  LoadedNet out;
  out.features = map.features().config();
  const int hidden = map.variant() == Variant::kSpatial ? 0 : map.lstm().hidden_size();
  out.net =
      Net(map.variant(), map.features().spatial_size(), map.components(), hidden, map.max_kappa());
  torch::NoGradGuard no_grad;
  for (auto& item : out.net->named_parameters()) {
    const std::string& key = item.key();
    const auto dot = key.rfind('.');
    const auto a = f.ReadFloat("/weights/" + key.substr(0, dot) + "/" + key.substr(dot + 1));
    FS_THROW_UNLESS(static_cast<std::int64_t>(a.Size()) == item.value().numel(), path, ": tensor ",
                    key, " has ", a.Size(), " values, the network needs ", item.value().numel());
    item.value().copy_(
        torch::from_blob(const_cast<float*>(a.data.data()), item.value().sizes(), torch::kFloat32));
  }
  out.net->eval();
  return out;
}

TrainingSummary TrainNet(const ExperimentConfig& c, const FeatureConfig& features, Variant variant,
                         const DirectionalSamples& train, const DirectionalSamples& val,
                         const std::string& dir, bool resume, const TrainHooks& hooks) {
  const std::string artifact = dir + "/model.h5";
  if (fs::exists(artifact)) {
    TrainingSummary s;
    s.reason = TerminationReason::kAlreadyComplete;
    return s;
  }
  fs::create_directories(dir);
  RunPaths run{dir};
  const bool can_resume = resume && fs::exists(run.Checkpoint());
  torch::manual_seed(static_cast<std::uint64_t>(c.seed));
  Net net = MakeNet(c, features, variant);
  DirectionalTask task(net, Features(features), train, val, PenaltyOf(c.network));
  TrainConfig tc = c.train;
  if (variant == Variant::kSpatial && c.network.spatial_epochs > 0)
    tc.epochs = c.network.spatial_epochs;
  if (c.data.train_fraction < 1.0) {
    // Epochs count passes over a full training split: a fraction f trains epochs / f passes (the
    // same number of optimiser steps), patience likewise.
    tc.epochs = static_cast<int>(std::ceil(tc.epochs / c.data.train_fraction));
    tc.patience = static_cast<int>(std::ceil(tc.patience / c.data.train_fraction));
  }
  TrainingSummary s = Train(&task, tc, run, static_cast<std::uint64_t>(c.seed), can_resume, hooks);
  WriteTrainingSummary(dir + "/training_summary.json", s);
  if (s.reason == TerminationReason::kInterrupted) return s;
  const std::string ckpt =
      fs::exists(run.BestCheckpoint()) ? run.BestCheckpoint() : run.Checkpoint();
  FS_THROW_UNLESS(fs::exists(ckpt), dir, ": training produced no checkpoint (", ToString(s.reason),
                  ")");
  Net best = MakeNet(c, features, variant);
  LoadCheckpointModel(ckpt, best.ptr().get());
  WriteArtifact(*best, features, config::ToYaml(c), c.seed, artifact);
  (void)Map::Load(artifact);  // the engine loads what was written
  return s;
}

std::vector<std::pair<std::string, Score>> EvaluateSplit(
    const ExperimentConfig& c, const FeatureConfig& f, const DirectionalSamples& train_all,
    const DirectionalSamples& test, const std::string& work_dir, const TrainHooks& hooks,
    bool* interrupted) {
  std::vector<std::pair<std::string, Score>> out;
  if (interrupted) *interrupted = false;
  VonMisesMixtureBatch batch;
  const auto [train, val] =
      SplitVal(train_all, c.eval.val_fraction, static_cast<std::uint64_t>(c.seed) + 17);
  const std::vector<Variant> variants = TrainedVariants(c);
  for (const Variant v : variants) {
    const std::string dir = work_dir + "/" + VariantName(v);
    const TrainingSummary s = TrainNet(c, f, v, train, val, dir, true, hooks);
    if (s.reason == TerminationReason::kInterrupted) {
      if (interrupted) *interrupted = true;
      return out;
    }
    const Map map = Map::Load(dir + "/model.h5");
    auto ws = map.MakeWorkspace();
    map.Query(test.x, test.y, test.t, &ws, &batch);
    out.push_back({VariantName(v), ScoreOf(c.eval, batch, test.theta)});
  }
  std::vector<std::pair<std::string, GridConfig>> grids{
      {"grid_um", GridConfigOf(c, f, GridKind::kUnimodal, false)},
      {"grid_mm", GridConfigOf(c, f, GridKind::kMultimodal, false)}};
  if (c.eval.dense) {
    grids.push_back({"grid_um_dense", GridConfigOf(c, f, GridKind::kUnimodal, true)});
    grids.push_back({"grid_mm_dense", GridConfigOf(c, f, GridKind::kMultimodal, true)});
  }
  for (const auto& [name, g] : grids) {
    const GridMap grid = GridMap::Fit(train_all, g);
    grid.Query(test.x, test.y, &batch);
    out.push_back({name, ScoreOf(c.eval, batch, test.theta)});
  }
  // Nearest training headings at the same cap: the trivial baseline every table carries. With
  // more than one time point, time is a coordinate scaled so that one temporal length scale
  // weighs as one spatial length scale.
  const bool timed = f.time_points > 1;
  for (const int k : {1, c.eval.knn_k}) {
    if (k == c.eval.knn_k && k == 1) continue;  // knn with k = 1 is nn1
    FS_THROW_UNLESS(k <= train_all.size(), "eval.knn_k = ", k, " exceeds the ", train_all.size(),
                    " training samples of a fold");
    KnnConfig kc;
    kc.k = k;
    kc.kappa = c.network.max_kappa;
    kc.use_time = timed;
    kc.time_scale = timed ? f.length_scale / f.time_length_scale : 1.0;
    const KnnMap knn = KnnMap::Fit(train_all, kc);
    knn.Query(test.x, test.y, test.t, &batch);
    out.push_back({k == 1 ? "nn1" : "knn", ScoreOf(c.eval, batch, test.theta)});
  }
  return out;
}

// ---------------------------------------------------------------------------------------------

double MethodMetrics::MeanAl() const { return Mean(al); }
double MethodMetrics::MeanMre() const { return Mean(mre); }
double MethodMetrics::StdAl() const { return Std(al); }
double MethodMetrics::StdMre() const { return Std(mre); }

const MethodMetrics* EvalReport::Find(const std::string& method) const {
  for (const auto& m : methods)
    if (m.method == method) return &m;
  return nullptr;
}

std::string EvalReport::ToJson() const {
  std::ostringstream os;
  os << "{\n";
  auto list = [](const std::vector<double>& v) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + Num(v[i]);
    return s + "]";
  };
  for (const auto& m : methods) {
    os << "  \"" << m.method << "\": {\"al\": " << Num(m.MeanAl())
       << ", \"mre\": " << Num(m.MeanMre()) << ", \"al_std\": " << Num(m.StdAl())
       << ", \"mre_std\": " << Num(m.StdMre()) << ", \"al_folds\": " << list(m.al)
       << ", \"mre_folds\": " << list(m.mre) << ", \"mre_w\": " << Num(Mean(m.mre_w));
    for (std::size_t i = 0; i < m.al_caps.size() && i < metric_caps.size(); ++i)
      os << ", \"al_cap" << CapName(metric_caps[i]) << "\": " << Num(Mean(m.al_caps[i]));
    os << "},\n";
  }
  os << "  \"samples\": " << samples << ",\n  \"folds\": " << folds << ",\n  \"folds_by\": \""
     << folds_by << "\""
     << ",\n  \"folds_evaluated\": " << folds_evaluated
     << ",\n  \"resolution\": {\"cells_x\": " << features.cells_x
     << ", \"cells_y\": " << features.cells_y
     << ", \"inducing_points\": " << features.cells_x * features.cells_y
     << ", \"length_scale\": " << Num(features.length_scale)
     << ", \"time_points\": " << features.time_points
     << ", \"time_length_scale\": " << Num(features.time_length_scale) << ", \"extent\": ["
     << Num(features.x_min) << ", " << Num(features.x_max) << ", " << Num(features.y_min) << ", "
     << Num(features.y_max) << "], \"time_range\": [" << Num(features.t_min) << ", "
     << Num(features.t_max) << "]}\n}\n";
  return os.str();
}

std::string EvalReport::ToCsv() const {
  std::ostringstream os;
  os << "method,fold,al,mre,mre_w";
  for (const double cap : metric_caps) os << ",al_cap" << CapName(cap);
  os << "\n";
  for (const auto& m : methods)
    for (std::size_t k = 0; k < m.al.size(); ++k) {
      os << m.method << "," << k << "," << Num(m.al[k]) << "," << Num(m.mre[k]) << ","
         << Num(k < m.mre_w.size() ? m.mre_w[k] : NAN);
      for (std::size_t i = 0; i < metric_caps.size(); ++i)
        os << "," << Num(i < m.al_caps.size() && k < m.al_caps[i].size() ? m.al_caps[i][k] : NAN);
      os << "\n";
    }
  return os.str();
}

std::string EvalReport::BriefReport() const {
  std::ostringstream os;
  os << "directional eval (" << samples << " samples, " << folds_evaluated << "/" << folds
     << " folds, " << features.cells_x * features.cells_y << " inducing points / cells):";
  for (const auto& m : methods)
    os << "\n  " << std::left << std::setw(16) << m.method << " AL " << std::setprecision(4)
       << m.MeanAl() << " +- " << m.StdAl() << "   MRE " << m.MeanMre() << " +- " << m.StdMre();
  return os.str();
}

namespace {
/// The run's artifacts: fold 0's networks (trained on fold 0's training split). model.h5 is the
/// spatiotemporal one, or the spatial one when only that was trained.
void PublishFoldZero(const ExperimentConfig& c, const std::string& run_dir) {
  if (c.eval.spatiotemporal)
    fs::copy_file(run_dir + "/folds/0/spatiotemporal/model.h5", run_dir + "/model.h5",
                  fs::copy_options::overwrite_existing);
  if (c.eval.spatial)
    fs::copy_file(run_dir + "/folds/0/spatial/model.h5",
                  run_dir + (c.eval.spatiotemporal ? "/model_spatial.h5" : "/model.h5"),
                  fs::copy_options::overwrite_existing);
}
}  // namespace

std::string ExportRun(const std::string& run_dir) {
  const auto c = config::LoadExperimentConfig<ExperimentConfig>(run_dir + "/config.yaml");
  const DirectionalSamples data = LoadSamples(c);
  const FeatureConfig f = ResolveExtent(c.features, data.x, data.y, data.t);
  const std::vector<Variant> variants = TrainedVariants(c);
  const int folds = EvaluatedFolds(c);
  for (int k = 0; k < folds; ++k) {
    for (const Variant v : variants) {
      const std::string dir = run_dir + "/folds/" + std::to_string(k) + "/" + VariantName(v);
      const RunPaths run{dir};
      const std::string ckpt =
          fs::exists(run.BestCheckpoint()) ? run.BestCheckpoint() : run.Checkpoint();
      FS_THROW_UNLESS(fs::exists(ckpt), dir, ": no checkpoint to export (fold ", k,
                      " is not trained yet; ", "continue with train --resume)");
      Net best = MakeNet(c, f, v);
      LoadCheckpointModel(ckpt, best.ptr().get());
      WriteArtifact(*best, f, config::ToYaml(c), c.seed, dir + "/model.h5");
      (void)Map::Load(dir + "/model.h5");
    }
  }
  PublishFoldZero(c, run_dir);
  log::Info("exported ", folds, " folds x ", variants.size(), " networks; ", run_dir,
            "/model.h5 is fold 0's");
  return run_dir + "/model.h5";
}

namespace {
/// Every fold: train what is not trained yet (nothing, when evaluating a finished run), query
/// the networks and fit the grids; then eval.json, eval.csv, the run's artifacts and plots.
RunResult RunFolds(const ExperimentConfig& c, const std::string& run_dir, const TrainHooks& hooks);
}  // namespace

RunResult RunExperiment(const ExperimentConfig& c, const std::string& run_dir, bool resume,
                        const TrainHooks& hooks) {
  StartRunDirectory(run_dir, config::ToYaml(c), resume, kDirectionalRunRules);
  log::Info(resume ? "resuming" : "training", " directional maps in ", run_dir, " (seed ", c.seed,
            ")");
  return RunFolds(c, run_dir, hooks);
}

EvalReport EvaluateRun(const ExperimentConfig& c, const std::string& run_dir) {
  for (int k = 0; k < EvaluatedFolds(c); ++k)
    for (const Variant v : TrainedVariants(c)) {
      const std::string dir = run_dir + "/folds/" + std::to_string(k) + "/" + VariantName(v);
      FS_THROW_UNLESS(fs::exists(dir + "/model.h5"), dir,
                      ": no model.h5 (the run is not finished; continue it with train --resume)");
    }
  log::SetFile(run_dir + "/log.txt");
  log::Info("evaluating directional maps in ", run_dir);
  return RunFolds(c, run_dir, {}).report;
}

namespace {
/// Guards a fold directory against being evaluated on rows other than those it was trained for:
/// the first use writes WORK/test_rows.hash (count and FNV-1a of the test rows); later uses must
/// match. A fold trained before the hash existed (point folds, the old default) is accepted only
/// with eval.folds_by: point.
void CheckFoldRows(const std::string& work, const std::vector<Eigen::Index>& rows, bool by_path) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const Eigen::Index r : rows) {
    h ^= static_cast<std::uint64_t>(r);
    h *= 1099511628211ULL;
  }
  std::ostringstream want;
  want << rows.size() << " " << h;
  const std::string path = work + "/test_rows.hash";
  if (fs::exists(path)) {
    std::ifstream in(path);
    std::string have;
    std::getline(in, have);
    FS_THROW_UNLESS(have == want.str(), path, ": this fold was trained with other test rows (",
                    have, " vs ", want.str(),
                    "); eval.folds, eval.folds_by, the data or the seed differ from the run's");
    return;
  }
  FS_THROW_UNLESS(!by_path || !fs::exists(work), work,
                  " holds a fold trained before path folds existed (point folds): evaluate it "
                  "with eval.folds_by=point");
  fs::create_directories(work);
  WriteFileAtomically(path, want.str() + "\n");
}

RunResult RunFolds(const ExperimentConfig& c, const std::string& run_dir, const TrainHooks& hooks) {
  const DirectionalSamples data = LoadSamples(c);
  const FeatureConfig f = ResolveExtent(c.features, data.x, data.y, data.t);
  (void)Features(f);  // checks the resolved extent
  log::Info(data.size(), " samples; ", f.cells_x, " x ", f.cells_y,
            " spatial inducing points over x [", f.x_min, ", ", f.x_max, "], y [", f.y_min, ", ",
            f.y_max, "], ", f.time_points, " temporal over [", f.t_min, ", ", f.t_max, "] s");
  const bool by_path = c.eval.folds_by == FoldsBy::kPath;
  FS_THROW_UNLESS(!by_path || static_cast<Eigen::Index>(data.path.size()) == data.size(),
                  "eval.folds_by: path, but the samples carry no path ids (use point)");
  std::vector<std::vector<Eigen::Index>> folds;
  try {
    folds =
        by_path
            ? GroupedKFoldTestIndices(data.path, c.eval.folds, static_cast<std::uint64_t>(c.seed))
            : KFoldTestIndices(data.size(), c.eval.folds, static_cast<std::uint64_t>(c.seed));
  } catch (const Error& e) {
    Fail("eval.folds = ", c.eval.folds, " with eval.folds_by = ", by_path ? "path" : "point", ": ",
         e.what());
  }
  const int evaluate = EvaluatedFolds(c);

  RunResult result;
  EvalReport& report = result.report;
  report.samples = data.size();
  report.folds = c.eval.folds;
  report.folds_by = by_path ? "path" : "point";
  report.metric_caps = c.eval.metric_caps;
  report.features = f;
  for (int k = 0; k < evaluate; ++k) {
    const auto& test_idx = folds[static_cast<std::size_t>(k)];
    DirectionalSamples train = data.Select(Complement(data.size(), test_idx));
    if (c.data.train_fraction < 1.0)
      train = train.Select(RandomSubset(train.size(), c.data.train_fraction,
                                        static_cast<std::uint64_t>(c.seed) + 1000 + k));
    const DirectionalSamples test = data.Select(test_idx);
    log::Info("fold ", k + 1, "/", evaluate, ": ", train.size(), " training, ", test.size(),
              " test samples");
    const std::string work = run_dir + "/folds/" + std::to_string(k);
    CheckFoldRows(work, test_idx, by_path);
    bool interrupted = false;
    const auto scores = EvaluateSplit(c, f, train, test, work, hooks, &interrupted);
    if (interrupted) {
      result.interrupted = true;
      return result;
    }
    for (const auto& [name, score] : scores) {
      MethodMetrics* m = nullptr;
      for (auto& existing : report.methods)
        if (existing.method == name) m = &existing;
      if (!m) {
        report.methods.push_back({name, {}, {}, {}, {}});
        m = &report.methods.back();
        m->al_caps.resize(score.al_caps.size());
      }
      m->al.push_back(score.al);
      m->mre.push_back(score.mre);
      m->mre_w.push_back(score.mre_w);
      for (std::size_t i = 0; i < score.al_caps.size(); ++i)
        m->al_caps[i].push_back(score.al_caps[i]);
      log::Info("  fold ", k + 1, " ", name, ": AL ", score.al, " MRE ", score.mre, " MRE_w ",
                score.mre_w);
    }
    ++report.folds_evaluated;
  }
  PublishFoldZero(c, run_dir);
  WriteFileAtomically(run_dir + "/eval.json", report.ToJson());
  WriteFileAtomically(run_dir + "/eval.csv", report.ToCsv());
  if (c.eval.plots) {
    fs::create_directories(run_dir + "/plots");
    const Map first = Map::Load(run_dir + "/model.h5");
    std::unique_ptr<Map> sp;
    if (c.eval.spatial && c.eval.spatiotemporal)
      sp = std::make_unique<Map>(Map::Load(run_dir + "/model_spatial.h5"));
    PlotMaps(data, first, sp.get(), c.eval, static_cast<std::uint64_t>(c.seed), run_dir + "/plots");
  }
  log::Info(report.BriefReport());
  return result;
}

}  // namespace

}  // namespace foresight::directional
