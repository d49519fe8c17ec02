// The SPAN predictor as an experiment kind (thesis ch 5): train -> export -> eval.

#include <filesystem>
#include <fstream>
#include <iostream>

#include "core/error.h"
#include "training/kinds.h"
#include "training/span/eval.h"
#include "training/span/pipeline.h"

namespace foresight::span {
namespace fs = std::filesystem;

namespace {

void TrainSpanRun(const TrainRequest& req, const std::string& embedded_default) {
  const auto c =
      LoadRequestConfig<ExperimentConfig>(req, embedded_default, "configs/quickstart.yaml");
  TrainingSummary s;
  {
    // Ctrl-C ends the current epoch early; the last checkpoint stays valid for --resume. Export
    // and eval afterwards get the previous handlers back.
    const ScopedInterruptFlag interrupt;
    TrainHooks hooks;
    hooks.interrupt = interrupt.flag();
    s = TrainRun(c, req.run_dir, req.resume, hooks);
  }
  WriteTrainingSummary(req.run_dir + "/training_summary.json", s);
  std::cout << s.BriefReport() << "\n";
  if (s.reason == TerminationReason::kInterrupted && s.epochs_completed == 0)
    Fail("interrupted in epoch 1 before the first checkpoint; nothing was saved to resume from");
  if (s.reason == TerminationReason::kInterrupted)
    Fail("interrupted after epoch ", s.epochs_completed, "; continue with --resume --run-dir ",
         req.run_dir);
  if (s.best_epoch < 0)
    Fail(req.run_dir, ": training produced no usable checkpoint (", ToString(s.reason), ")");
  const std::string artifact = ExportRun(req.run_dir);
  std::cout << "artifact: " << artifact << "\n";
  if (!req.evaluate) return;
  const EvalReport r = Evaluate(c, artifact, req.run_dir);
  std::cout << "eval (" << r.windows << " test windows): ADE " << r.model.ade << " FDE "
            << r.model.fde << " NLL " << r.model.nll << " | constant velocity ADE " << r.cv.ade
            << " FDE " << r.cv.fde << " NLL " << r.cv.nll << "\n"
            << "wrote " << req.run_dir << "/eval.json and " << req.run_dir
            << "/plots/samples.png\n";
}

std::string EvaluateRun(const std::string& run_dir, const std::vector<std::string>& overrides) {
  const auto c = LoadRunConfig<ExperimentConfig>(run_dir, overrides);
  const std::string artifact = run_dir + "/model.h5";
  FS_THROW_UNLESS(fs::exists(artifact), artifact, ": not found (run `foresight export ", run_dir,
                  "` first)");
  return Evaluate(c, artifact, run_dir).ToJson(c.eval.num_samples);
}

}  // namespace

ExperimentKind Kind(const std::string& embedded_default) {
  ExperimentKind k;
  k.tag = "span_predictor";
  k.summary = "SPAN pedestrian predictor (thesis ch 5, 7)";
  k.configs = "configs/quickstart.yaml, configs/span/*.yaml, configs/navigation/predictor*.yaml";
  k.resumable = true;
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.train = [embedded_default](const TrainRequest& req) { TrainSpanRun(req, embedded_default); };
  k.export_run = [](const std::string& run_dir) { return ExportRun(run_dir); };
  k.evaluate = EvaluateRun;
  SetBenchStep(&k);
  return k;
}

}  // namespace foresight::span
