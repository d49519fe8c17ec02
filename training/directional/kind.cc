// Continuous spatiotemporal directional maps as an experiment kind (thesis ch 4).

#include <iostream>

#include "core/error.h"
#include "training/directional/pipeline.h"
#include "training/kinds.h"

namespace foresight::directional {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "directional";
  k.summary = "Directional maps (thesis ch 4)";
  k.configs = "configs/directional/*.yaml";
  k.resumable = true;
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.train = [](const TrainRequest& req) {
    FS_THROW_UNLESS(
        req.config != "default" && !req.config.empty(),
        "directional maps have no embedded default config; name one (configs/directional/*.yaml)");
    const auto c = config::LoadExperimentConfig<ExperimentConfig>(req.config, req.overrides);
    RunResult r;
    {
      const ScopedInterruptFlag interrupt;
      TrainHooks hooks;
      hooks.interrupt = interrupt.flag();
      r = RunExperiment(c, req.run_dir, req.resume,
                        hooks);  // trains, exports and evaluates each fold
    }
    if (r.interrupted) Fail("interrupted; continue with --resume --run-dir ", req.run_dir);
    std::cout << r.report.BriefReport() << "\n"
              << "wrote " << req.run_dir << "/model.h5, eval.json, eval.csv and plots/*.png\n";
  };
  k.export_run = ExportRun;
  k.evaluate = [](const std::string& run_dir, const std::vector<std::string>& overrides) {
    // Every fold again with its trained networks; the run's config.yaml is left as it was.
    const auto c = LoadRunConfig<ExperimentConfig>(run_dir, overrides);
    return EvaluateRun(c, run_dir).ToJson();
  };
  SetBenchStep(&k);
  return k;
}

}  // namespace foresight::directional
