// OTNet as an experiment kind (thesis ch 6): trajectory distributions in maps never seen before.

#include <iostream>

#include "core/error.h"
#include "training/kinds.h"
#include "training/otnet/pipeline.h"
#include "training/trainer.h"

namespace foresight::otnet {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "otnet";
  k.summary = "OTNet: trajectory distributions in new maps from Hausdorff map similarities (ch 6)";
  k.configs = "configs/otnet/*.yaml";
  k.resumable = true;
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.train = [](const TrainRequest& req) {
    FS_THROW_UNLESS(req.config != "default" && !req.config.empty(),
                    "otnet has no embedded default config; name one (configs/otnet/*.yaml)");
    const auto c = config::LoadExperimentConfig<ExperimentConfig>(req.config, req.overrides);
    bool done = false;
    {
      const ScopedInterruptFlag interrupt;
      done = TrainOtnetRun(c, req.run_dir, req.resume, interrupt.flag());
    }
    if (!done) Fail("interrupted; continue with --resume --run-dir ", req.run_dir);
    std::cout << "wrote " << req.run_dir << "/model.h5\n";
    if (req.evaluate) {
      EvaluateOtnetRun(c, req.run_dir);
      std::cout << "wrote " << req.run_dir << "/eval.json\n";
    }
  };
  k.export_run = ExportOtnetRun;
  k.evaluate = [](const std::string& run_dir, const std::vector<std::string>& overrides) {
    // The split is the run's: another seed or data section would score training maps as test
    // (data.root only says where the same files are).
    for (const std::string& o : overrides)
      FS_THROW_UNLESS(
          o.rfind("seed=", 0) != 0 && (o.rfind("data.", 0) != 0 || o.rfind("data.root=", 0) == 0),
          "eval ", run_dir, ": override '", o,
          "' would change the map split the run was trained on; train a new run");
    const auto c = LoadRunConfig<ExperimentConfig>(run_dir, overrides);
    return EvaluateOtnetRun(c, run_dir);
  };
  SetBenchStep(&k);
  return k;
}

}  // namespace foresight::otnet
