// Occupancy maps as an experiment kind (thesis ch 3): Fast-BHM, BHM, Hilbert map, grid, fusion.
// Eigen learners write their artifact when trained, so export only checks that it loads.

#include <filesystem>
#include <iostream>

#include "core/error.h"
#include "inference/mapping/occupancy_map.h"
#include "training/kinds.h"
#include "training/occupancy/pipeline.h"

namespace foresight::occupancy {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "occupancy.";
  k.tag_is_prefix = true;
  k.summary = "Occupancy maps and their fusion (thesis ch 3)";
  k.configs = "configs/occupancy/*.yaml";
  k.resumable = false;  // one pass of seconds
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.train = [](const TrainRequest& req) {
    FS_THROW_UNLESS(
        req.config != "default" && !req.config.empty(),
        "occupancy maps have no embedded default config; name one (configs/occupancy/*.yaml)");
    const auto c = config::LoadExperimentConfig<ExperimentConfig>(req.config, req.overrides);
    FS_THROW_UNLESS(!req.resume,
                    "--resume: occupancy maps train in one pass (seconds); run again into a new "
                    "or empty --run-dir");
    TrainRun(c, req.run_dir);
    std::cout << "artifact: " << req.run_dir << "/model.h5\n";
    if (!req.evaluate) return;
    std::cout << EvaluateRun(c, req.run_dir) << "wrote " << req.run_dir
              << "/eval.json, roc.csv and plots/map.png\n";
  };
  k.export_run = [](const std::string& run_dir) {
    const std::string artifact = run_dir + "/model.h5";
    FS_THROW_UNLESS(std::filesystem::exists(artifact), artifact,
                    ": not found (train the map first)");
    (void)LoadMap(artifact);  // the engine loads what training wrote
    return artifact;
  };
  k.evaluate = [](const std::string& run_dir, const std::vector<std::string>& overrides) {
    return EvaluateRun(LoadRunConfig<ExperimentConfig>(run_dir, overrides), run_dir);
  };
  SetBenchStep(&k);
  return k;
}

}  // namespace foresight::occupancy
