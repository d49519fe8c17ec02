// Structurally constrained motion prediction as an experiment kind (thesis ch 7).

#include <iostream>

#include "core/error.h"
#include "training/constrained/pipeline.h"
#include "training/kinds.h"
#include "training/trainer.h"

namespace foresight::constrained {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "constrained";
  k.summary =
      "structurally constrained prediction: matrix-normal mixture prior projected onto a "
      "collision chance constraint by SLSQP, vs KTM, CV, naive network (ch 7)";
  k.configs = "configs/constrained/*.yaml";
  k.resumable = true;
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.train = [](const TrainRequest& req) {
    FS_THROW_UNLESS(req.config != "default" && !req.config.empty(),
                    "constrained has no embedded default config; name one "
                    "(configs/constrained/*.yaml)");
    const auto c = config::LoadExperimentConfig<ExperimentConfig>(req.config, req.overrides);
    bool done = false;
    {
      const ScopedInterruptFlag interrupt;
      done = TrainConstrainedRun(c, req.run_dir, req.resume, interrupt.flag());
    }
    if (!done) Fail("interrupted; continue with --resume --run-dir ", req.run_dir);
    std::cout << "wrote " << req.run_dir << "/prior.h5\n";
    if (req.evaluate) {
      EvaluateConstrainedRun(c, req.run_dir);
      std::cout << "wrote " << req.run_dir << "/eval.json\n";
    }
  };
  k.export_run = ExportConstrainedRun;
  k.evaluate = [](const std::string& run_dir, const std::vector<std::string>& overrides) {
    // The split is the run's: another seed, data, split or windows section would score training
    // tracks as test (data.root only says where the same files are).
    for (const std::string& o : overrides) {
      const bool data_root = o.rfind("data.root=", 0) == 0;
      const bool changes_split =
          o.rfind("seed=", 0) == 0 || (o.rfind("data.", 0) == 0 && !data_root) ||
          o.rfind("split.", 0) == 0 || o.rfind("windows.", 0) == 0 || o.rfind("map.", 0) == 0;
      FS_THROW_UNLESS(!changes_split, "eval ", run_dir, ": override '", o,
                      "' would change the split, windows or maps the run was trained with; train a "
                      "new run");
    }
    const auto c = LoadRunConfig<ExperimentConfig>(run_dir, overrides);
    return EvaluateConstrainedRun(c, run_dir);
  };
  k.no_step_hint = "its projection times are in eval.json (solve_time_ms, unprojected_time_ms)";
  return k;
}

}  // namespace foresight::constrained
