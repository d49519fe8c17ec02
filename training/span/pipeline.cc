#include "training/span/pipeline.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/h5.h"
#include "core/log.h"
#include "inference/engine/artifact.h"
#include "inference/prediction/span_predictor.h"
#include "models/span/span_data.h"
#include "models/span/span_net.h"
#include "training/run_dir.h"
#include "training/span/calibration.h"
#include "training/tensor_eigen.h"

namespace foresight::span {
namespace fs = std::filesystem;

namespace {
class SpanTask : public TrainingTask {
 public:
  SpanTask(Net net, const HeadLayout& layout, torch::Tensor x_train, torch::Tensor w_train,
           torch::Tensor x_val, torch::Tensor w_val)
      : net_(std::move(net)),
        layout_(layout),
        x_train_(std::move(x_train)),
        w_train_(std::move(w_train)),
        x_val_(std::move(x_val)),
        w_val_(std::move(w_val)) {}

  torch::nn::Module& module() override { return *net_; }
  std::int64_t num_train() const override { return x_train_.size(0); }

  torch::Tensor BatchLoss(const torch::Tensor& idx) override {
    const auto raw = net_->forward(x_train_.index_select(0, idx));
    return MixtureNll(DecodeHead(raw, layout_), w_train_.index_select(0, idx), layout_).mean();
  }

  double ValidationLoss() override {
    double sum = 0;
    const std::int64_t n = x_val_.size(0);
    FS_THROW_UNLESS(n > 0, "no validation windows to compute the validation loss on");
    for (std::int64_t b = 0; b < n; b += 4096) {
      const std::int64_t len = std::min<std::int64_t>(4096, n - b);
      const auto raw = net_->forward(x_val_.narrow(0, b, len));
      sum += MixtureNll(DecodeHead(raw, layout_), w_val_.narrow(0, b, len), layout_)
                 .sum()
                 .item<double>();
    }
    return sum / static_cast<double>(n);
  }

 private:
  Net net_;
  HeadLayout layout_;
  torch::Tensor x_train_, w_train_, x_val_, w_val_;
};

}  // namespace

TrainingSummary TrainRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
                         const TrainHooks& hooks) {
  StartRunDirectory(run_dir, config::ToYaml(c), resume, kRunRules);
  log::Info(resume ? "resuming" : "training", " span_predictor in ", run_dir, " (seed ", c.seed,
            ")");

  const TrackSplit split = LoadPedestrianSplits(c.data, static_cast<std::uint64_t>(c.seed));
  const WindowSet train_w = MakeWindows(split.train, c.windows);
  const WindowSet val_w = MakeWindows(split.val, c.windows);
  log::Info("windows: ", train_w.size(), " train, ", val_w.size(), " val");
  const int length = c.windows.observed + c.windows.predicted;
  FS_THROW_UNLESS(train_w.size() > 0, "no training windows of ", length,
                  " points in the training tracks");
  // The validation loss chooses the best checkpoint and drives early stopping (train.patience).
  FS_THROW_UNLESS(val_w.size() > 0,
                  "no validation windows: no validation track has windows.observed + "
                  "windows.predicted = ",
                  length, " points (",
                  c.data.val_files.empty() ? "raise data.val_fraction" : "check data.val_files",
                  "); the validation loss chooses the best checkpoint and drives early stopping");
  ModelSpec spec = ModelSpecOf(c);
  spec.seconds_per_step = train_w.seconds_per_step;
  if (c.augment.Copies() > 1)
    log::Info("augmenting the training windows x", c.augment.Copies(), " (augment.*)");
  return TrainOnWindows(spec, train_w, val_w, c.train, c.seed, run_dir, resume, hooks, c.augment);
}

ModelSpec ModelSpecOf(const ExperimentConfig& c) {
  ModelSpec s;
  s.observed = c.windows.observed;
  s.predicted = c.windows.predicted;
  s.seconds_per_step = SecondsPerStep(c.data);
  s.basis = c.basis;
  s.network = c.network;
  return s;
}

HeadLayout LayoutOf(const ModelSpec& s) {
  HeadLayout l;
  l.basis = s.basis.num_centres;
  l.components = s.network.components;
  l.u_param = s.network.u_param;
  return l;
}

Samples MakeSamples(const ModelSpec& s, const WindowSet& windows) {
  const TimeBasis basis = MakeFutureBasis(s.basis, s.predicted, s.seconds_per_step);
  return MakeSamples(windows, basis, s.basis, s.network.rotate_to_heading,
                     s.network.residual_to_constant_velocity);
}

torch::Tensor ToFloatTensor(const Eigen::MatrixXd& m) {
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = m.cast<float>();
  return torch::from_blob(rm.data(), {rm.rows(), rm.cols()}, torch::kFloat32).clone();
}

Eigen::MatrixXd InputNormalisation::Apply(const Eigen::MatrixXd& x) const {
  return (x.rowwise() - mean.transpose()).array().rowwise() / std.transpose().array();
}

InputNormalisation FitInputNormalisation(const Eigen::MatrixXd& x) {
  InputNormalisation n;
  n.mean = x.colwise().mean().transpose();
  n.std = ((x.rowwise() - n.mean.transpose()).array().square().colwise().mean()).sqrt().transpose();
  // Constant features (the ego origin) pass through. Nearly constant ones are floored at 1 cm:
  // e.g. the ego y of the first point is 0 except in the rare windows too short to rotate (standing
  // pedestrians), and dividing those by a micrometre-scale std feeds the network inputs of 1e3+
  // (non-finite losses on crowd data with many standing pedestrians).
  constexpr double kMinStd = 0.01;  // m
  for (Eigen::Index i = 0; i < n.std.size(); ++i) {
    if (!(n.std[i] > 1e-6))
      n.std[i] = 1.0;
    else
      n.std[i] = std::max(n.std[i], kMinStd);
  }
  return n;
}

void WriteInputNormalisation(const std::string& path, const InputNormalisation& n) {
  h5::WriteAtomically(path, [&](h5::File* f) {
    f->WriteMatrix("/input_mean", n.mean);
    f->WriteMatrix("/input_std", n.std);
  });
}

InputNormalisation ReadInputNormalisation(const std::string& path) {
  h5::File f = h5::File::Open(path);
  return {f.ReadMatrixD("/input_mean").col(0), f.ReadMatrixD("/input_std").col(0)};
}

TrainingSummary TrainNet(const ModelSpec& spec, const Samples& train_s, const Samples& val_s,
                         const TrainConfig& train_config, std::int64_t seed,
                         const std::string& run_dir, bool resume, const TrainHooks& hooks) {
  FS_THROW_UNLESS(train_s.inputs.rows() > 0, run_dir, ": no training samples for the SPAN net");
  FS_THROW_UNLESS(val_s.inputs.rows() > 0, run_dir,
                  ": no validation samples for the SPAN net (the validation loss chooses the best "
                  "checkpoint)");
  const HeadLayout layout = LayoutOf(spec);
  const std::int64_t m = layout.basis;
  FS_THROW_UNLESS(train_s.targets.cols() == 2 * m && val_s.targets.cols() == 2 * m &&
                      val_s.inputs.cols() == train_s.inputs.cols(),
                  run_dir, ": SPAN samples of ", train_s.inputs.cols(), " / ", val_s.inputs.cols(),
                  " inputs and ", train_s.targets.cols(), " / ", val_s.targets.cols(),
                  " targets, expected equal inputs and 2 x basis = ", 2 * m, " targets");
  std::filesystem::create_directories(run_dir);
  const std::string norm_path = run_dir + "/normalisation.h5";
  const InputNormalisation norm =
      resume ? ReadInputNormalisation(norm_path) : FitInputNormalisation(train_s.inputs);
  FS_THROW_UNLESS(norm.mean.size() == train_s.inputs.cols(), norm_path, ": normalisation of ",
                  norm.mean.size(), " inputs, the samples have ", train_s.inputs.cols());
  if (!resume) WriteInputNormalisation(norm_path, norm);

  torch::manual_seed(static_cast<std::uint64_t>(seed));
  Net net(static_cast<int>(train_s.inputs.cols()), spec.network, layout);
  auto w_train = ToFloatTensor(train_s.targets).view({train_s.targets.rows(), m, 2});
  auto w_val = ToFloatTensor(val_s.targets).view({val_s.targets.rows(), m, 2});
  SpanTask task(net, layout, ToFloatTensor(norm.Apply(train_s.inputs)), w_train,
                ToFloatTensor(norm.Apply(val_s.inputs)), w_val);
  return Train(&task, train_config, RunPaths{run_dir}, static_cast<std::uint64_t>(seed), resume,
               hooks);
}

TrainingSummary TrainOnWindows(const ModelSpec& spec, const WindowSet& train_w,
                               const WindowSet& val_w, const TrainConfig& train_config,
                               std::int64_t seed, const std::string& run_dir, bool resume,
                               const TrainHooks& hooks, const AugmentConfig& augment) {
  FS_THROW_UNLESS(train_w.size() > 0, run_dir, ": no training windows");
  FS_THROW_UNLESS(val_w.size() > 0, run_dir, ": no validation windows");
  FS_THROW_UNLESS(train_w.observed == spec.observed && train_w.predicted == spec.predicted &&
                      val_w.observed == spec.observed && val_w.predicted == spec.predicted,
                  run_dir, ": windows of ", train_w.observed, " + ", train_w.predicted,
                  " (train) / ", val_w.observed, " + ", val_w.predicted,
                  " (val) points, the model expects ", spec.observed, " + ", spec.predicted);
  return TrainNet(spec, Augment(MakeSamples(spec, train_w), augment), MakeSamples(spec, val_w),
                  train_config, seed, run_dir, resume, hooks);
}

Mlp ToEngineMlp(torch::nn::Module& net, const std::vector<std::string>& names) {
  const auto params = net.named_parameters();
  std::vector<DenseLayer> layers;
  for (const std::string& name : names)
    layers.push_back(
        {ToEigenMatrix(params[name + ".weight"]), ToEigenVector(params[name + ".bias"])});
  return Mlp(std::move(layers));
}

PredictorWeights WeightsFromCheckpoint(const ModelSpec& spec, int input_dim,
                                       const std::string& checkpoint,
                                       const std::string& normalisation_file) {
  const HeadLayout layout = LayoutOf(spec);
  Net net(input_dim, spec.network, layout);
  LoadCheckpointModel(checkpoint, net.ptr().get());
  const InputNormalisation norm = ReadInputNormalisation(normalisation_file);
  FS_THROW_UNLESS(norm.mean.size() == input_dim, normalisation_file, ": normalisation of ",
                  norm.mean.size(), " inputs, the net takes ", input_dim);
  const TimeBasis basis = MakeFutureBasis(spec.basis, spec.predicted, spec.seconds_per_step);
  PredictorWeights w;
  w.observed = spec.observed;
  w.predicted = spec.predicted;
  w.seconds_per_step = spec.seconds_per_step;
  w.rotate_to_heading = spec.network.rotate_to_heading;
  w.residual_to_constant_velocity = spec.network.residual_to_constant_velocity;
  w.layout = layout;
  w.basis_centres = basis.centres();
  w.basis_gamma = basis.gamma();
  w.input_mean = norm.mean;
  w.input_std = norm.std;
  w.layer_names = net->DenseLayerNames();
  w.mlp = ToEngineMlp(*net, w.layer_names);
  return w;
}

std::string ExportRun(const std::string& run_dir) {
  const std::string config_path = run_dir + "/config.yaml";
  FS_THROW_UNLESS(fs::exists(config_path), run_dir, ": not a run directory (no config.yaml)");
  const ExperimentConfig c = config::LoadExperimentConfig<ExperimentConfig>(config_path, {});
  RunPaths run{run_dir};
  const std::string ckpt =
      fs::exists(run.BestCheckpoint()) ? run.BestCheckpoint() : run.Checkpoint();
  FS_THROW_UNLESS(fs::exists(ckpt), run_dir, ": no checkpoint to export (train first)");
  const std::string out = run_dir + "/model.h5";
  PredictorWeights w = WeightsFromCheckpoint(ModelSpecOf(c), 2 * c.windows.observed, ckpt,
                                             run_dir + "/normalisation.h5");
  if (c.calibrate_covariance) {
    // The scale is fitted with the engine on an uncalibrated copy; model.h5 is written once, so
    // a failure here (no data, no validation windows) leaves no uncalibrated model.h5 behind.
    const std::string uncalibrated = run_dir + "/model.uncalibrated.h5";
    Predictor::Save(uncalibrated, w, config::ToYaml(c), c.seed);
    const Predictor model = Predictor::Load(uncalibrated);
    fs::remove(uncalibrated);
    const TrackSplit split = LoadPedestrianSplits(c.data, static_cast<std::uint64_t>(c.seed));
    const WindowSet val = MakeWindows(split.val, c.windows);
    FS_THROW_UNLESS(val.size() > 0, run_dir,
                    ": calibrate_covariance needs validation windows and there are none");
    const std::vector<PointTerms> terms = CovarianceScaleTerms(model, val);
    w.covariance_scale = FitCovarianceScale(terms);
    log::Info("covariance scale fitted on ", val.size(),
              " validation windows: c = ", w.covariance_scale, " (validation NLL per point ",
              ScaledNll(terms, 1.0), " -> ", ScaledNll(terms, w.covariance_scale), ")");
  }
  Predictor::Save(out, w, config::ToYaml(c), c.seed);
  // Prove the artifact loads in the engine before reporting success.
  (void)Predictor::Load(out);
  log::Info("exported ", ckpt, " -> ", out);
  return out;
}

}  // namespace foresight::span
