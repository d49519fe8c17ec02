// `foresight train | export | eval | docs`

#include <filesystem>
#include <fstream>
#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/log.h"
#include "embedded_config.h"
#include "training/directional_config.h"
#include "training/directional_pipeline.h"
#include "training/navigation_config.h"
#include "training/occupancy_config.h"
#include "training/span_eval.h"
#include "training/span_pipeline.h"

namespace foresight::app {
namespace fs = std::filesystem;

namespace {

/// CONFIG may be a file or "default" (the embedded configs/quickstart.yaml).
SpanExperimentConfig LoadConfig(const std::string& path, const std::vector<std::string>& overrides) {
  if (path.empty() || path == "default")
    return SpanConfigFromYaml(kEmbeddedDefaultConfig, "<embedded configs/quickstart.yaml>", overrides);
  return LoadSpanConfig(path, overrides);
}

std::string DefaultRunDir(const std::string& config_path) {
  const std::string stem = config_path.empty() || config_path == "default" ? "quickstart"
                                                                          : fs::path(config_path).stem().string();
  return "runs/" + stem;
}

/// Cross-validated directional maps into run_dir (resume continues unfinished fold networks).
void RunDirectional(const std::string& config_path, const std::vector<std::string>& overrides,
                    const std::string& run_dir, bool resume) {
  const DirectionalExperimentConfig c = LoadDirectionalConfig(config_path, overrides);
  DirectionalRunResult r;
  {
    const ScopedInterruptFlag interrupt;
    TrainHooks hooks;
    hooks.interrupt = interrupt.flag();
    r = RunDirectionalExperiment(c, run_dir, resume, hooks);
  }
  if (r.interrupted) Fail("interrupted; continue with --resume --run-dir ", run_dir);
  std::cout << r.report.BriefReport() << "\n"
            << "wrote " << run_dir << "/model.h5, eval.json, eval.csv and plots/*.png\n";
}

struct TrainArgs {
  std::string config, run_dir;
  std::vector<std::string> overrides;
  bool resume = false, no_eval = false;
};

}  // namespace

bool IsDirectionalConfig(const std::string& path) {
  if (path.empty() || path == "default") return false;
  const YAML::Node root = config::LoadYamlFile(path);
  if (!root.IsMap() || !root["model"] || !root["model"].IsScalar()) return false;
  return root["model"].as<std::string>() == "directional";
}

void AddTrainCommands(CLI::App* app) {
  AddBenchDirectionalCommand(app->get_subcommand("bench"));  // `bench` is registered first (main.cc)
  auto targs = std::make_shared<TrainArgs>();
  auto* train = app->add_subcommand("train", "train a model from a YAML config, export it and evaluate it");
  train->add_option("config", targs->config, "config file, or 'default' for the embedded quickstart")->required();
  train->add_option("overrides", targs->overrides, "key.path=value overrides of the config");
  train->add_option("--run-dir", targs->run_dir, "run directory (default runs/<config name>)");
  train->add_flag("--resume", targs->resume, "continue from the run directory's last checkpoint");
  train->add_flag("--no-eval", targs->no_eval, "stop after export");
  train->callback([targs] {
    const std::string run_dir = targs->run_dir.empty() ? DefaultRunDir(targs->config) : targs->run_dir;
    if (IsOccupancyConfig(targs->config)) {
      TrainOccupancy(targs->config, targs->overrides, run_dir, targs->resume);
      return;
    }
    if (IsDirectionalConfig(targs->config)) {
      RunDirectional(targs->config, targs->overrides, run_dir, targs->resume);
      return;
    }
    const SpanExperimentConfig c = LoadConfig(targs->config, targs->overrides);
    TrainingSummary s;
    {
      // Ctrl-C ends the current epoch early; the last checkpoint stays valid for --resume. Export
      // and eval afterwards get the previous handlers back.
      const ScopedInterruptFlag interrupt;
      TrainHooks hooks;
      hooks.interrupt = interrupt.flag();
      s = TrainSpan(c, run_dir, targs->resume, hooks);
    }
    std::ofstream(run_dir + "/training_summary.json") << s.ToJson();
    std::cout << s.BriefReport() << "\n";
    if (s.reason == TerminationReason::kInterrupted && s.epochs_completed == 0)
      Fail("interrupted in epoch 1 before the first checkpoint; nothing was saved to resume from");
    if (s.reason == TerminationReason::kInterrupted)
      Fail("interrupted after epoch ", s.epochs_completed, "; continue with --resume --run-dir ", run_dir);
    if (s.best_epoch < 0) Fail(run_dir, ": training produced no usable checkpoint (", ToString(s.reason), ")");
    const std::string artifact = ExportSpan(run_dir);
    std::cout << "artifact: " << artifact << "\n";
    if (!targs->no_eval) {
      const SpanEvalReport r = EvaluateSpan(c, artifact, run_dir);
      std::cout << "eval (" << r.windows << " test windows): ADE " << r.model.ade << " FDE " << r.model.fde
                << " NLL " << r.model.nll << " | constant velocity ADE " << r.cv.ade << " FDE " << r.cv.fde
                << " NLL " << r.cv.nll << "\n"
                << "wrote " << run_dir << "/eval.json and " << run_dir << "/plots/samples.png\n";
    }
  });

  auto export_dir = std::make_shared<std::string>();
  auto* exp = app->add_subcommand("export", "write RUN_DIR/model.h5 from the best checkpoint");
  exp->add_option("run_dir", *export_dir, "run directory")->required()->check(CLI::ExistingDirectory);
  exp->callback([export_dir] { std::cout << ExportSpan(*export_dir) << "\n"; });

  auto eargs = std::make_shared<TrainArgs>();
  auto* eval = app->add_subcommand("eval", "evaluate RUN_DIR/model.h5 on the config's test split");
  eval->add_option("config", eargs->config, "config file, or 'default'")->required();
  eval->add_option("overrides", eargs->overrides, "key.path=value overrides of the config");
  eval->add_option("--run-dir", eargs->run_dir, "run directory holding model.h5")->required();
  eval->callback([eargs] {
    if (IsOccupancyConfig(eargs->config)) {
      EvalOccupancy(eargs->config, eargs->overrides, eargs->run_dir);
      return;
    }
    if (IsDirectionalConfig(eargs->config)) {
      // Re-evaluates every fold with the trained networks (resume skips finished training).
      const DirectionalExperimentConfig c = LoadDirectionalConfig(eargs->config, eargs->overrides);
      std::cout << RunDirectionalExperiment(c, eargs->run_dir, true).report.ToJson();
      return;
    }
    const SpanExperimentConfig c = LoadConfig(eargs->config, eargs->overrides);
    const std::string artifact = eargs->run_dir + "/model.h5";
    FS_THROW_UNLESS(fs::exists(artifact), artifact, ": not found (run `foresight export ", eargs->run_dir, "` first)");
    const SpanEvalReport r = EvaluateSpan(c, artifact, eargs->run_dir);
    std::cout << r.ToJson(c.eval.num_samples);
  });

  auto docs_out = std::make_shared<std::string>();
  auto* docs = app->add_subcommand("docs", "generate reference documentation");
  docs->require_subcommand(1);
  auto* cfg = docs->add_subcommand("config", "print the config reference (every key with its default) as Markdown");
  cfg->add_option("-o,--output", *docs_out, "write to this file instead of stdout");
  cfg->callback([docs_out] {
    std::string text =
        "# Config reference\n\nGenerated by `foresight docs config -o docs/config_reference.md`; do not edit.\n"
        "Every key of a SPAN predictor experiment (`configs/quickstart.yaml`, `configs/span/*.yaml`) with its "
        "default. Override any key on the command line as `key.path=value`.\n\n" +
        config::ReferenceTable<SpanExperimentConfig>() +
        "\n## Occupancy-map experiments\n\nEvery key of an occupancy config (`configs/occupancy/*.yaml`, "
        "`model: occupancy.*`) with its default.\n\n" +
        config::ReferenceTable<OccupancyExperimentConfig>() +
        "\n## Directional-map experiments\n\nEvery key of a directional config (`configs/directional/*.yaml`, "
        "`model: directional`) with its default.\n\n" +
        config::ReferenceTable<DirectionalExperimentConfig>() +
        "\n## Navigation experiments\n\nEvery key of a navigation config (`configs/navigation/*.yaml`, "
        "`model: navigation`, run by `foresight navigate`) with its default.\n\n" +
        config::ReferenceTable<NavigationExperimentConfig>();
    if (docs_out->empty()) std::cout << text;
    else std::ofstream(*docs_out) << text;
  });
}

}  // namespace foresight::app
