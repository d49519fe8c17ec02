#include "training/diffeo/pipeline.h"

#include <filesystem>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "training/diffeo/demos.h"
#include "training/diffeo/eval.h"
#include "training/diffeo/train.h"
#include "training/kinds.h"
#include "training/run_dir.h"

namespace foresight::imitation {
namespace fs = std::filesystem;

namespace {
const RunDirectoryRules kDiffeoRunRules{{"shapes", "models", "eval.json"}, true};
}  // namespace

bool TrainRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
              const std::atomic<bool>* interrupt) {
  StartRunDirectory(run_dir, config::ToYaml(c), resume, kDiffeoRunRules);
  const std::vector<PreparedDemos> sets = LoadDemos(c);
  log::Info(resume ? "resuming" : "starting", " diffeomorphic templates in ", run_dir, ": ",
            sets.size(), " shape(s), seed ", c.seed);
  for (const PreparedDemos& d : sets) {
    const ShapePaths paths(run_dir, d.name);
    if (resume && ShapeExported(c, paths)) {
      log::Info(d.name, ": already exported, skipped");
      continue;
    }
    log::Info(d.name, ": ", d.demos.demos.size(), " demos (", d.train.size(),
              " trained on), goal "
              "spread ",
              d.spread.max_distance, " (extent ", d.spread.extent, ")");
    if (!TrainShape(c, d, paths, resume, interrupt)) return false;
    ExportShape(c, d, paths);
  }
  return true;
}

std::string ExportRun(const std::string& run_dir) {
  const auto c = LoadRunConfig<ExperimentConfig>(run_dir, {});
  std::string first;
  for (const PreparedDemos& d : LoadDemos(c)) {
    const ShapePaths paths(run_dir, d.name);
    ExportShape(c, d, paths);
    if (first.empty()) first = paths.Template();
  }
  return first;
}

std::string EvaluateRun(const ExperimentConfig& c, const std::string& run_dir) {
  std::vector<std::pair<std::string, Scores>> shapes;
  for (const PreparedDemos& d : LoadDemos(c)) {
    const ShapePaths paths(run_dir, d.name);
    FS_THROW_UNLESS(fs::exists(paths.Template()), run_dir, ": ", paths.Template(),
                    " is missing; train (or export) the run first");
    const std::string eflow = c.eflow.enabled ? paths.Eflow() : "";
    const std::string plots = c.eval.plots ? run_dir + "/plots" : "";
    log::Info(d.name, ": evaluating");
    shapes.emplace_back(d.name, c.data.source == DemoSource::kTaskSpace
                                    ? EvaluateTaskSpaceShape(c, d, paths.Template(), eflow, plots)
                                    : EvaluatePlanarShape(c, d, paths.Template(), eflow, plots));
  }
  const std::string json = EvalJson(shapes);
  WriteFileAtomically(run_dir + "/eval.json", json);
  return json;
}

}  // namespace foresight::imitation
