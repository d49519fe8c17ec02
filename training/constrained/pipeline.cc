#include "training/constrained/pipeline.h"

#include <filesystem>

#include "core/error.h"
#include "core/log.h"
#include "training/constrained/data.h"
#include "training/constrained/eval.h"
#include "training/constrained/learners.h"
#include "training/kinds.h"
#include "training/run_dir.h"
#include "training/trainer.h"

namespace foresight::constrained {
namespace fs = std::filesystem;

namespace {

const RunDirectoryRules kConstrainedRunRules{{"prior", "prior.h5", "eval.json"}, true};

LearnerSpec SpecOf(const ExperimentConfig& c, double seconds_per_step) {
  LearnerSpec s;
  s.observed = c.windows.observed;
  s.predicted = c.windows.predicted;
  s.seconds_per_step = seconds_per_step;
  s.seed = c.seed;
  s.basis = c.basis;
  s.network = c.network;
  s.train = c.train;
  return s;
}

}  // namespace

bool TrainConstrainedRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
                         const std::atomic<bool>* interrupt) {
  const std::string yaml = config::ToYaml(c);
  StartRunDirectory(run_dir, yaml, resume, kConstrainedRunRules);
  log::Info(resume ? "resuming" : "starting", " constrained prediction in ", run_dir, ", seed ",
            c.seed);
  const ConstrainedData d = LoadConstrainedData(c);
  const LearnerSpec spec = SpecOf(c, d.train.windows.seconds_per_step);
  const RunArtifacts art = ArtifactsOf(c, run_dir);
  TrainHooks hooks;
  hooks.interrupt = interrupt;
  // A learner whose artifact exists is done (artifacts are written atomically after training).
  // Its directory exists once it started, so only a started learner resumes.
  auto stage = [&](const std::string& artifact, const std::string& dir, auto&& train) {
    if (artifact.empty() || fs::exists(artifact)) return true;
    // The trainer creates checkpoints/ before epoch 1; only a written checkpoint can be resumed
    // (a run killed in epoch 1 starts that learner again).
    const bool started = fs::exists(RunPaths{dir}.Checkpoint());
    log::Info("constrained: ", started && resume ? "resuming " : "training ", dir);
    return train(dir, resume && started);
  };
  if (!stage(art.prior, run_dir + "/prior", [&](const std::string& dir, bool r) {
        return TrainPrior(spec, d.train.windows, d.val.windows, dir, r, hooks, art.prior, yaml);
      }))
    return false;
  KtmSpec ks;
  ks.references = c.ktm.references;
  ks.lengthscale = c.ktm.lengthscale;
  if (!stage(art.ktm, run_dir + "/ktm", [&](const std::string& dir, bool r) {
        return TrainKtm(spec, ks, d.train.windows, d.val.windows, dir, r, hooks, art.ktm, yaml);
      }))
    return false;
  NaiveSpec ns;
  ns.hidden = c.naive.hidden;
  if (!stage(art.naive, run_dir + "/naive", [&](const std::string& dir, bool r) {
        return TrainNaive(spec, ns, d.train.windows, d.val.windows, dir, r, hooks, art.naive, yaml);
      }))
    return false;
  return FitSceneMaps(c, d.split.test, run_dir, interrupt);
}

std::string ExportConstrainedRun(const std::string& run_dir) {
  const auto c = LoadRunConfig<ExperimentConfig>(run_dir, {});
  const ConstrainedData d = LoadConstrainedData(c);
  const LearnerSpec spec = SpecOf(c, d.train.windows.seconds_per_step);
  const RunArtifacts art = ArtifactsOf(c, run_dir);
  const std::string yaml = config::ToYaml(c);
  ExportPrior(spec, run_dir + "/prior", art.prior, yaml);
  if (!art.ktm.empty())
    ExportKtm(spec, KtmSpec{c.ktm.references, c.ktm.lengthscale}, run_dir + "/ktm", art.ktm, yaml);
  if (!art.naive.empty())
    ExportNaive(spec, NaiveSpec{c.naive.hidden}, run_dir + "/naive", art.naive, yaml);
  log::Info("constrained: exported ", art.prior, art.ktm.empty() ? "" : ", " + art.ktm,
            art.naive.empty() ? "" : ", " + art.naive);
  return art.prior;
}

std::string EvaluateConstrainedRun(const ExperimentConfig& c, const std::string& run_dir) {
  return EvaluateConstrained(c, LoadConstrainedData(c), run_dir);
}

}  // namespace foresight::constrained
