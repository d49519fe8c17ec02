// Self-supervised GFCS as an experiment kind (thesis ch 9): the energy-model sampler trained on
// its own GFCS solutions, exported for the plan harness and the manipulation runtime.

#include <iostream>

#include "core/error.h"
#include "training/distributed.h"
#include "training/gfcs/pipeline.h"
#include "training/kinds.h"
#include "training/trainer.h"

namespace foresight::gfcs {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "gfcs";
  k.summary = "Self-supervised GFCS: energy-model sampler warm-starting CMA-ES (thesis ch 9)";
  k.configs = "configs/gfcs/*.yaml";
  k.resumable = true;
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.train = [](const TrainRequest& req) {
    FS_THROW_UNLESS(req.config != "default" && !req.config.empty(),
                    "gfcs has no embedded default config; name one (configs/gfcs/*.yaml)");
    const auto c = config::LoadExperimentConfig<ExperimentConfig>(req.config, req.overrides);
    bool done = false;
    {
      const ScopedInterruptFlag interrupt;
      done = TrainRun(c, req.run_dir, req.resume, interrupt.flag(), req.evaluate);
    }
    if (!done) Fail("interrupted; continue with --resume --run-dir ", req.run_dir);
    if (dist::DefaultGroup()->rank() != 0) return;  // rank 0 exports and evaluates
    std::cout << "wrote " << req.run_dir << "/model.h5\n";
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
  k.no_step_hint =
      "time its runtime with `foresight bench` on a manipulation config "
      "(configs/manipulation/*.yaml)";
  return k;
}

}  // namespace foresight::gfcs
