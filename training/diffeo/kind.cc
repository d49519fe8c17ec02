// Diffeomorphic templates as an experiment kind (thesis ch 8): stable imitation by RBF flows,
// obstacle and bias transforms, the Euclideanizing-Flows baseline.

#include <iostream>

#include "core/error.h"
#include "training/diffeo/pipeline.h"
#include "training/kinds.h"
#include "training/trainer.h"

namespace foresight::imitation {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "diffeo";
  k.summary =
      "Diffeomorphic templates: stable imitation bending around new obstacles (thesis ch 8)";
  k.configs = "configs/diffeo/*.yaml";
  k.resumable = true;
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.train = [](const TrainRequest& req) {
    FS_THROW_UNLESS(req.config != "default" && !req.config.empty(),
                    "diffeo has no embedded default config; name one (configs/diffeo/*.yaml)");
    const auto c = config::LoadExperimentConfig<ExperimentConfig>(req.config, req.overrides);
    bool done = false;
    {
      const ScopedInterruptFlag interrupt;
      done = TrainRun(c, req.run_dir, req.resume, interrupt.flag());
    }
    if (!done) Fail("interrupted; continue with --resume --run-dir ", req.run_dir);
    std::cout << "wrote " << req.run_dir << "/models\n";
    if (req.evaluate) {
      EvaluateRun(c, req.run_dir);
      std::cout << "wrote " << req.run_dir << "/eval.json\n";
    }
  };
  k.export_run = ExportRun;
  k.evaluate = [](const std::string& run_dir, const std::vector<std::string>& overrides) {
    const auto c = LoadRunConfig<ExperimentConfig>(run_dir, overrides);
    return EvaluateRun(c, run_dir);
  };
  SetBenchStep(&k);
  return k;
}

}  // namespace foresight::imitation
