// Continuous spatiotemporal directional maps as an experiment kind (thesis ch 4).

#include <iostream>

#include "core/error.h"
#include "training/directional/pipeline.h"
#include "training/kinds.h"

namespace foresight {

ExperimentKind DirectionalKind() {
  ExperimentKind k;
  k.tag = "directional";
  k.summary = "Directional maps (thesis ch 4)";
  k.configs = "configs/directional/*.yaml";
  k.resumable = true;
  k.reference = [] { return config::ReferenceTable<DirectionalExperimentConfig>(); };
  k.train = [](const TrainRequest& req) {
    FS_THROW_UNLESS(
        req.config != "default" && !req.config.empty(),
        "directional maps have no embedded default config; name one (configs/directional/*.yaml)");
    const auto c =
        config::LoadExperimentConfig<DirectionalExperimentConfig>(req.config, req.overrides);
    DirectionalRunResult r;
    {
      const ScopedInterruptFlag interrupt;
      TrainHooks hooks;
      hooks.interrupt = interrupt.flag();
      r = RunDirectionalExperiment(c, req.run_dir, req.resume,
                                   hooks);  // trains, exports and evaluates each fold
    }
    if (r.interrupted) Fail("interrupted; continue with --resume --run-dir ", req.run_dir);
    std::cout << r.report.BriefReport() << "\n"
              << "wrote " << req.run_dir << "/model.h5, eval.json, eval.csv and plots/*.png\n";
  };
  k.export_run = ExportDirectionalRun;
  k.evaluate = [](const std::string& run_dir, const std::vector<std::string>& overrides) {
    // Every fold again with its trained networks; the run's config.yaml is left as it was.
    const auto c = LoadRunConfig<DirectionalExperimentConfig>(run_dir, overrides);
    return EvaluateDirectionalRun(c, run_dir).ToJson();
  };
  SetDirectionalBench(&k);
  return k;
}

}  // namespace foresight
