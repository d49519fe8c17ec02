#include "training/otnet/train.h"

#include <filesystem>

#include "core/error.h"
#include "core/log.h"
#include "models/otnet/otnet_net.h"
#include "training/otnet/task.h"
#include "training/trainer.h"

namespace foresight::otnet {
namespace fs = std::filesystem;

namespace {

MixtureFamily MixtureFamilyOf(const ExperimentConfig& c) {
  return c.otnet.family == Family::kLaplace ? MixtureFamily::kLaplace : MixtureFamily::kNormal;
}

OtnetNet MakeNet(const ExperimentConfig& c, const OtnetPrepared& p) {
  torch::manual_seed(static_cast<std::uint64_t>(c.seed));
  OtnetNetOptions o;
  o.inputs = p.encoder.size();
  o.hidden = c.otnet.hidden;
  o.components = c.otnet.components;
  o.weights = p.basis.weights();
  o.dropout = c.otnet.dropout;
  o.family = MixtureFamilyOf(c);
  return OtnetNet(o);
}

OtnetNormalisation Normalisation(const OtnetPrepared& p) {
  return OtnetNormalisation::Fit(p.train.phi, p.train.w);
}

torch::Tensor ToTensor(const Eigen::MatrixXd& m) {
  torch::Tensor t = torch::empty({m.rows(), m.cols()}, torch::kFloat32);
  auto a = t.accessor<float, 2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) a[i][j] = static_cast<float>(m(i, j));
  return t;
}

torch::Tensor Standardised(const Eigen::MatrixXd& m, const Eigen::VectorXd& mean,
                           const Eigen::VectorXd& std) {
  const Eigen::MatrixXd s =
      (m.rowwise() - mean.transpose()).array().rowwise() / std.transpose().array();
  return ToTensor(s);
}

torch::Tensor Indices(const std::vector<std::int64_t>& v) {
  return torch::tensor(v, torch::kInt64);
}

}  // namespace

OtnetPrepared PrepareOtnet(const ExperimentConfig& c) {
  OtnetPrepared p;
  p.data = LoadOtnetData(c);
  p.basis = MakeBasis(c);
  log::Info("otnet: basis M = ", p.basis.size(), ", reconstruction RMSE ",
            ReconstructionRmse(p.basis, p.data.train), " cells on the training trajectories");
  p.encoder = MakeEncoder(c, p.data.train);
  log::Info("otnet: database of ", p.encoder.size(), " representative maps, l_H ",
            c.otnet.length_scale);
  p.train = EncodeSplit(p.encoder, p.basis, p.data.train);
  p.val = EncodeSplit(p.encoder, p.basis, p.data.val);
  return p;
}

bool TrainOtnet(const ExperimentConfig& c, const OtnetPrepared& p, const std::string& run_dir,
                bool resume, const std::atomic<bool>* interrupt) {
  const OtnetNormalisation n = Normalisation(p);
  OtnetNet net = MakeNet(c, p);
  OtnetTask task(net, Standardised(p.train.phi, n.input_mean, n.input_std),
                 Indices(p.train.map_index), Standardised(p.train.w, n.weight_mean, n.weight_std),
                 Standardised(p.val.phi, n.input_mean, n.input_std), Indices(p.val.map_index),
                 Standardised(p.val.w, n.weight_mean, n.weight_std));
  const RunPaths run{run_dir};
  TrainHooks hooks;
  hooks.interrupt = interrupt;
  const TrainingSummary summary = Train(&task, c.train, run, static_cast<std::uint64_t>(c.seed),
                                        resume && fs::exists(run.Checkpoint()), hooks);
  log::Info("otnet: ", summary.BriefReport());
  FS_THROW_UNLESS(summary.reason != TerminationReason::kNonFiniteLoss,
                  "otnet: the loss became non-finite; lower train.learning_rate");
  return summary.reason != TerminationReason::kInterrupted;
}

std::string ExportOtnet(const ExperimentConfig& c, const OtnetPrepared& p,
                        const std::string& run_dir) {
  const std::string best = RunPaths{run_dir}.BestCheckpoint();
  FS_THROW_UNLESS(fs::exists(best), run_dir, ": ", best, " is missing; train the run first");
  OtnetNet net = MakeNet(c, p);
  LoadCheckpointModel(best, net.get());
  net->eval();
  const OtnetNormalisation norm = Normalisation(p);
  OtnetModel model(p.encoder, p.basis, ExportMlp(net, norm), MixtureFamilyOf(c),
                   c.otnet.components);
  // The engine clamps log-scales where training did (in standardised units).
  model.SetLogScaleOffset(norm.weight_std.array().log().matrix());
  const std::string path = run_dir + "/model.h5";
  model.Save(path, config::ToYaml(c), c.seed);
  return path;
}

}  // namespace foresight::otnet
