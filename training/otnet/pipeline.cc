#include "training/otnet/pipeline.h"

#include <filesystem>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "training/kinds.h"
#include "training/otnet/eval.h"
#include "training/otnet/train.h"
#include "training/run_dir.h"

namespace foresight::otnet {
namespace fs = std::filesystem;

namespace {
const RunDirectoryRules kOtnetRunRules{{"checkpoints", "model.h5", "eval.json"}, true};
}  // namespace

bool TrainOtnetRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
                   const std::atomic<bool>* interrupt) {
  StartRunDirectory(run_dir, config::ToYaml(c), resume, kOtnetRunRules);
  log::Info(resume ? "resuming" : "starting", " OTNet in ", run_dir, ", seed ", c.seed);
  const OtnetPrepared p = PrepareOtnet(c);
  if (!TrainOtnet(c, p, run_dir, resume, interrupt)) return false;
  log::Info("otnet: wrote ", ExportOtnet(c, p, run_dir));
  return true;
}

std::string ExportOtnetRun(const std::string& run_dir) {
  const auto c = LoadRunConfig<ExperimentConfig>(run_dir, {});
  return ExportOtnet(c, PrepareOtnet(c), run_dir);
}

std::string EvaluateOtnetRun(const ExperimentConfig& c, const std::string& run_dir) {
  const std::string artifact = run_dir + "/model.h5";
  FS_THROW_UNLESS(fs::exists(artifact), run_dir, ": model.h5 is missing; train (or export) first");
  const OtnetData d = LoadOtnetData(c);
  const std::string json =
      EvaluateOtnet(c, d, artifact, c.eval.plots ? run_dir + "/plots" : std::string());
  WriteFileAtomically(run_dir + "/eval.json", json);
  return json;
}

}  // namespace foresight::otnet
