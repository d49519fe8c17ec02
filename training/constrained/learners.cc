#include "training/constrained/learners.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "core/ego_frame.h"
#include "core/error.h"
#include "core/h5.h"
#include "core/log.h"
#include "inference/prediction/naive_predictor.h"
#include "inference/prediction/span_predictor.h"
#include "models/constrained/naive_net.h"
#include "training/span/pipeline.h"
#include "training/trainer.h"

namespace foresight::constrained {
namespace fs = std::filesystem;

namespace {

span::ModelSpec SpanSpecOf(const LearnerSpec& s) {
  span::ModelSpec m;
  m.observed = s.observed;
  m.predicted = s.predicted;
  m.seconds_per_step = s.seconds_per_step;
  m.basis = s.basis;
  m.network = s.network;
  return m;
}

/// Both splits hold windows of the spec's shape and step.
void CheckWindows(const LearnerSpec& s, const WindowSet& train, const WindowSet& val,
                  const std::string& learner, const std::string& dir) {
  FS_THROW_UNLESS(train.size() > 0, learner, " in ", dir, ": no training windows");
  FS_THROW_UNLESS(val.size() > 0, learner, " in ", dir,
                  ": no validation windows (the validation loss chooses the best checkpoint)");
  for (const WindowSet* w : {&train, &val}) {
    const char* split = w == &train ? "training" : "validation";
    FS_THROW_UNLESS(w->observed == s.observed && w->predicted == s.predicted, learner, " in ", dir,
                    ": ", split, " windows of ", w->observed, " + ", w->predicted,
                    " points, the learner expects observed + predicted = ", s.observed, " + ",
                    s.predicted);
    FS_THROW_UNLESS(std::abs(w->seconds_per_step - s.seconds_per_step) <= 1e-9, learner, " in ",
                    dir, ": ", split, " windows every ", w->seconds_per_step,
                    " s, the learner expects seconds_per_step = ", s.seconds_per_step);
  }
}

/// The checkpoint to export: the best (validation) one, else the last.
std::string CheckpointToExport(const std::string& dir, const std::string& learner) {
  const RunPaths run{dir};
  const std::string ckpt =
      fs::exists(run.BestCheckpoint()) ? run.BestCheckpoint() : run.Checkpoint();
  FS_THROW_UNLESS(fs::exists(ckpt), learner, " in ", dir, ": no checkpoint to export");
  return ckpt;
}

bool Interrupted(const TrainingSummary& s, const std::string& learner, const std::string& dir) {
  log::Info(learner, " in ", dir, ": ", s.BriefReport());
  return s.reason == TerminationReason::kInterrupted;
}

/// Futures [N x 2f] of `w` in the ego frame of each window's past (x_1, y_1, ...).
Eigen::MatrixXd EgoFutures(const WindowSet& w, bool rotate) {
  Eigen::MatrixXd out(w.size(), 2 * w.predicted);
  for (int k = 0; k < w.size(); ++k) {
    const EgoFrame frame = EgoFrame::FromPast(
        w.observed, [&](int i) { return w.Past(k, i); }, rotate);
    for (int i = 0; i < w.predicted; ++i)
      out.row(k).segment<2>(2 * i) = frame.ToEgo(w.Future(k, i)).transpose();
  }
  return out;
}

/// Pasts [N x 2p] of `w` in their own ego frames.
Eigen::MatrixXd EgoPasts(const WindowSet& w, bool rotate) {
  Eigen::MatrixXd out(w.size(), 2 * w.observed);
  for (int k = 0; k < w.size(); ++k) {
    const EgoFrame frame = EgoFrame::FromPast(
        w.observed, [&](int i) { return w.Past(k, i); }, rotate);
    for (int i = 0; i < w.observed; ++i)
      out.row(k).segment<2>(2 * i) = frame.ToEgo(w.Past(k, i)).transpose();
  }
  return out;
}

/// Squared RMS pointwise distance between two segments of p points (rows [2p]).
template <class A, class B>
double SquaredRms(const A& q, const B& r) {
  return (q - r).squaredNorm() / (0.5 * static_cast<double>(q.size()));
}

/// Mean squared error of ego-frame futures (MSE over all 2f coordinates).
class NaiveTask : public TrainingTask {
 public:
  NaiveTask(NaiveNet net, torch::Tensor x_train, torch::Tensor y_train, torch::Tensor x_val,
            torch::Tensor y_val)
      : net_(std::move(net)),
        x_train_(std::move(x_train)),
        y_train_(std::move(y_train)),
        x_val_(std::move(x_val)),
        y_val_(std::move(y_val)) {}

  torch::nn::Module& module() override { return *net_; }
  std::int64_t num_train() const override { return x_train_.size(0); }

  torch::Tensor BatchLoss(const torch::Tensor& idx) override {
    return torch::mse_loss(net_->forward(x_train_.index_select(0, idx)),
                           y_train_.index_select(0, idx));
  }

  double ValidationLoss() override {
    const std::int64_t n = x_val_.size(0);
    double sum = 0;
    for (std::int64_t b = 0; b < n; b += 4096) {
      const std::int64_t len = std::min<std::int64_t>(4096, n - b);
      const auto d = net_->forward(x_val_.narrow(0, b, len)) - y_val_.narrow(0, b, len);
      sum += d.square().sum().item<double>();
    }
    return sum / static_cast<double>(n * y_val_.size(1));
  }

 private:
  NaiveNet net_;
  torch::Tensor x_train_, y_train_, x_val_, y_val_;
};

}  // namespace

Eigen::MatrixXd KtmFeatures(const Eigen::MatrixXd& ego_past, const Eigen::MatrixXd& references,
                            double lengthscale) {
  FS_THROW_UNLESS(ego_past.cols() == references.cols() && ego_past.cols() % 2 == 0,
                  "KtmFeatures: segments of ", ego_past.cols(), " numbers, references of ",
                  references.cols(), " (expected equal, 2 per point)");
  FS_THROW_UNLESS(lengthscale > 0, "KtmFeatures: lengthscale ", lengthscale, " must be positive");
  Eigen::MatrixXd out(ego_past.rows(), references.rows());
  const double inv = 1.0 / (2.0 * lengthscale * lengthscale);
  for (Eigen::Index n = 0; n < ego_past.rows(); ++n)
    for (Eigen::Index k = 0; k < references.rows(); ++k)
      out(n, k) = std::exp(-SquaredRms(ego_past.row(n), references.row(k)) * inv);
  return out;
}

Eigen::MatrixXd ChooseKtmReferences(const Eigen::MatrixXd& ego_past, int count, std::int64_t seed) {
  const Eigen::Index n = ego_past.rows();
  FS_THROW_UNLESS(count >= 1 && count <= n, "ktm.references = ", count,
                  " must be in [1, number of training windows = ", n, "]");
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  std::uniform_int_distribution<Eigen::Index> pick(0, n - 1);
  std::vector<Eigen::Index> chosen{pick(rng)};
  Eigen::VectorXd nearest = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
  while (static_cast<int>(chosen.size()) < count) {
    const Eigen::Index last = chosen.back();
    for (Eigen::Index i = 0; i < n; ++i)
      nearest[i] = std::min(nearest[i], SquaredRms(ego_past.row(i), ego_past.row(last)));
    Eigen::Index next = 0;
    nearest.maxCoeff(&next);  // first maximum: ties go to the lowest index
    chosen.push_back(next);
  }
  Eigen::MatrixXd refs(count, ego_past.cols());
  for (int k = 0; k < count; ++k) refs.row(k) = ego_past.row(chosen[static_cast<std::size_t>(k)]);
  return refs;
}

bool TrainPrior(const LearnerSpec& spec, const WindowSet& train, const WindowSet& val,
                const std::string& dir, bool resume, const TrainHooks& hooks,
                const std::string& artifact, const std::string& config_yaml) {
  FS_THROW_UNLESS(spec.network.u_param == UParam::kDiagonal, "prior in ", dir,
                  ": network.u_param = ", UParamName(spec.network.u_param),
                  ", the prior of constrained prediction needs diagonal (its KL and cost "
                  "gradients are in the log-diagonal of U)");
  CheckWindows(spec, train, val, "prior", dir);
  const span::ModelSpec s = SpanSpecOf(spec);
  log::Info(resume ? "resuming" : "training", " the prior in ", dir, " (", train.size(), " train, ",
            val.size(), " val windows)");
  const TrainingSummary summary =
      span::TrainOnWindows(s, train, val, spec.train, spec.seed, dir, resume, hooks);
  if (Interrupted(summary, "prior", dir)) return false;
  ExportPrior(spec, dir, artifact, config_yaml);
  return true;
}

void ExportPrior(const LearnerSpec& spec, const std::string& dir, const std::string& artifact,
                 const std::string& config_yaml) {
  const span::PredictorWeights w =
      span::WeightsFromCheckpoint(SpanSpecOf(spec), 2 * spec.observed,
                                  CheckpointToExport(dir, "prior"), dir + "/normalisation.h5");
  span::Predictor::Save(artifact, w, config_yaml, spec.seed);
  (void)span::Predictor::Load(artifact);
}

bool TrainKtm(const LearnerSpec& spec, const KtmSpec& ktm, const WindowSet& train,
              const WindowSet& val, const std::string& dir, bool resume, const TrainHooks& hooks,
              const std::string& artifact, const std::string& config_yaml) {
  CheckWindows(spec, train, val, "ktm", dir);
  FS_THROW_UNLESS(ktm.lengthscale > 0 && std::isfinite(ktm.lengthscale), "ktm in ", dir,
                  ": ktm.lengthscale = ", ktm.lengthscale, " must be positive");
  FS_THROW_UNLESS(ktm.references >= 1 && ktm.references <= train.size(), "ktm in ", dir,
                  ": ktm.references = ", ktm.references, " must be in [1, ", train.size(),
                  "] (the training windows)");
  const span::ModelSpec s = SpanSpecOf(spec);
  span::Samples train_s = span::MakeSamples(s, train);
  span::Samples val_s = span::MakeSamples(s, val);
  // The references are part of the training state: a resume reads them back.
  const std::string refs_path = dir + "/ktm_references.h5";
  Eigen::MatrixXd refs;
  if (resume) {
    FS_THROW_UNLESS(fs::exists(refs_path), refs_path, ": missing, nothing to resume");
    refs = h5::File::Open(refs_path).ReadMatrixD("/references", ktm.references, 2 * spec.observed);
  } else {
    refs = ChooseKtmReferences(train_s.inputs, ktm.references, spec.seed);
    fs::create_directories(dir);
    h5::WriteAtomically(refs_path, [&](h5::File* f) { f->WriteMatrix("/references", refs); });
  }
  train_s.inputs = KtmFeatures(train_s.inputs, refs, ktm.lengthscale);
  val_s.inputs = KtmFeatures(val_s.inputs, refs, ktm.lengthscale);
  log::Info(resume ? "resuming" : "training", " ktm in ", dir, " (", ktm.references,
            " references, l = ", ktm.lengthscale, " m)");
  const TrainingSummary summary =
      span::TrainNet(s, train_s, val_s, spec.train, spec.seed, dir, resume, hooks);
  if (Interrupted(summary, "ktm", dir)) return false;
  ExportKtm(spec, ktm, dir, artifact, config_yaml);
  return true;
}

void ExportKtm(const LearnerSpec& spec, const KtmSpec& ktm, const std::string& dir,
               const std::string& artifact, const std::string& config_yaml) {
  const std::string refs_path = dir + "/ktm_references.h5";
  FS_THROW_UNLESS(fs::exists(refs_path), refs_path, ": missing, nothing to export");
  span::PredictorWeights w = span::WeightsFromCheckpoint(
      SpanSpecOf(spec), ktm.references, CheckpointToExport(dir, "ktm"), dir + "/normalisation.h5");
  w.ktm_references =
      h5::File::Open(refs_path).ReadMatrixD("/references", ktm.references, 2 * spec.observed);
  w.ktm_lengthscale = ktm.lengthscale;
  span::Predictor::Save(artifact, w, config_yaml, spec.seed);
  (void)span::Predictor::Load(artifact);
}

bool TrainNaive(const LearnerSpec& spec, const NaiveSpec& naive, const WindowSet& train,
                const WindowSet& val, const std::string& dir, bool resume, const TrainHooks& hooks,
                const std::string& artifact, const std::string& config_yaml) {
  CheckWindows(spec, train, val, "naive", dir);
  const bool rotate = spec.network.rotate_to_heading;
  const Eigen::MatrixXd x_train = EgoPasts(train, rotate), x_val = EgoPasts(val, rotate);
  fs::create_directories(dir);
  const std::string norm_path = dir + "/normalisation.h5";
  const span::InputNormalisation norm =
      resume ? span::ReadInputNormalisation(norm_path) : span::FitInputNormalisation(x_train);
  FS_THROW_UNLESS(norm.mean.size() == x_train.cols(), norm_path, ": normalisation of ",
                  norm.mean.size(), " inputs, expected 2 x observed = ", x_train.cols());
  if (!resume) span::WriteInputNormalisation(norm_path, norm);
  log::Info(resume ? "resuming" : "training", " naive in ", dir, " (", train.size(), " train, ",
            val.size(), " val windows)");

  const int in = 2 * spec.observed, out = 2 * spec.predicted;
  torch::manual_seed(static_cast<std::uint64_t>(spec.seed));
  NaiveNet net(in, naive.hidden, out);
  NaiveTask task(
      net, span::ToFloatTensor(norm.Apply(x_train)), span::ToFloatTensor(EgoFutures(train, rotate)),
      span::ToFloatTensor(norm.Apply(x_val)), span::ToFloatTensor(EgoFutures(val, rotate)));
  const TrainingSummary summary =
      Train(&task, spec.train, RunPaths{dir}, static_cast<std::uint64_t>(spec.seed), resume, hooks);
  if (Interrupted(summary, "naive", dir)) return false;
  ExportNaive(spec, naive, dir, artifact, config_yaml);
  return true;
}

void ExportNaive(const LearnerSpec& spec, const NaiveSpec& naive, const std::string& dir,
                 const std::string& artifact, const std::string& config_yaml) {
  const int in = 2 * spec.observed, out = 2 * spec.predicted;
  const span::InputNormalisation norm = span::ReadInputNormalisation(dir + "/normalisation.h5");
  NaiveNet best(in, naive.hidden, out);
  LoadCheckpointModel(CheckpointToExport(dir, "naive"), best.ptr().get());
  NaivePredictorWeights w;
  w.observed = spec.observed;
  w.predicted = spec.predicted;
  w.seconds_per_step = spec.seconds_per_step;
  w.rotate_to_heading = spec.network.rotate_to_heading;
  w.input_mean = norm.mean;
  w.input_std = norm.std;
  w.layer_names = best->DenseLayerNames();
  w.mlp = span::ToEngineMlp(*best, w.layer_names);
  NaivePredictor::Save(artifact, w, config_yaml, spec.seed);
  (void)NaivePredictor::Load(artifact);
}

}  // namespace foresight::constrained
