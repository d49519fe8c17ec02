// `foresight train | export | eval | bench | docs config | kinds`: the same commands for every
// experiment kind. A command looks the kind up (from the config's `model:`, the run directory's
// config.yaml or the config stored in an artifact) and calls its step; no command names a method.

#include <filesystem>
#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/file_io.h"
#include "training/kinds.h"

namespace foresight::app {
namespace fs = std::filesystem;

namespace {

/// runs/<config name>, or runs/quickstart for the embedded default.
std::string DefaultRunDir(const std::string& config) {
  const bool embedded = config.empty() || config == "default";
  return "runs/" + (embedded ? std::string("quickstart") : fs::path(config).stem().string());
}

struct EvalArgs {
  std::string run_dir;
  std::vector<std::string> overrides;
};

}  // namespace

void AddExperimentCommands(CLI::App* app, std::shared_ptr<const ExperimentRegistry> registry) {
  auto req = std::make_shared<TrainRequest>();
  auto no_eval = std::make_shared<bool>(false);
  auto* train =
      app->add_subcommand("train", "train a model from a YAML config, export it and evaluate it");
  train->add_option("config", req->config, "config file, or 'default' for the embedded quickstart")
      ->required();
  train->add_option("overrides", req->overrides, "key.path=value overrides of the config");
  train->add_option("--run-dir", req->run_dir, "run directory (default runs/<config name>)");
  train->add_flag("--resume", req->resume,
                  "continue the killed run in --run-dir from its last checkpoint");
  train->add_flag("--no-eval", *no_eval, "stop after export");
  train->callback([registry, req, no_eval] {
    TrainRequest r = *req;
    if (r.run_dir.empty()) r.run_dir = DefaultRunDir(r.config);
    r.evaluate = !*no_eval;
    const ExperimentKind& kind = registry->ForConfig(r.config);
    if (!kind.train) kind.NoSuchStep("train");
    kind.train(r);
  });

  auto export_dir = std::make_shared<std::string>();
  auto* exp =
      app->add_subcommand("export", "write RUN_DIR's artifact (model.h5) from its best checkpoint");
  exp->add_option("run_dir", *export_dir, "run directory")
      ->required()
      ->check(CLI::ExistingDirectory);
  exp->callback([registry, export_dir] {
    const ExperimentKind& kind = registry->ForRun(*export_dir);
    if (!kind.export_run) kind.NoSuchStep("export");
    std::cout << kind.export_run(*export_dir) << "\n";
  });

  auto eargs = std::make_shared<EvalArgs>();
  auto* eval = app->add_subcommand(
      "eval", "evaluate RUN_DIR's artifact with the run's config; writes RUN_DIR/eval.json");
  eval->add_option("run_dir", eargs->run_dir, "run directory")
      ->required()
      ->check(CLI::ExistingDirectory);
  eval->add_option("overrides", eargs->overrides,
                   "key.path=value overrides of the run's config (e.g. data.root=...)");
  eval->callback([registry, eargs] {
    const ExperimentKind& kind = registry->ForRun(eargs->run_dir);
    if (!kind.evaluate) kind.NoSuchStep("eval");
    std::cout << kind.evaluate(eargs->run_dir, eargs->overrides);
  });

  auto breq = std::make_shared<BenchRequest>();
  auto bsettings = std::make_shared<std::vector<std::string>>();
  auto* bench = app->add_subcommand(
      "bench", "time TARGET's engine or runtime: figures side by side in one run (medians)");
  bench->add_option("target", breq->target, "a config, a run directory or an artifact (.h5)")
      ->required();
  bench->add_option("settings", *bsettings,
                    "key.path=value overrides of the config; bench.key=value options of the bench");
  bench->add_flag("--json", breq->json, "print one JSON object");
  bench->callback([registry, breq, bsettings] {
    BenchRequest r = *breq;
    for (const std::string& s : *bsettings) {
      if (s.rfind("bench.", 0) == 0)
        r.options.push_back(s.substr(6));
      else
        r.overrides.push_back(s);
    }
    const ExperimentKind& kind = registry->ForBenchTarget(&r);
    if (!kind.bench) kind.NoSuchStep("bench");
    kind.bench(r);
  });

  auto docs_out = std::make_shared<std::string>();
  auto* docs = app->add_subcommand("docs", "generate reference documentation");
  docs->require_subcommand(1);
  auto* cfg = docs->add_subcommand(
      "config", "print the config reference (every key of every kind) as Markdown");
  cfg->add_option("-o,--output", *docs_out, "write to this file instead of stdout");
  cfg->callback([registry, docs_out] {
    const std::string text = registry->ReferenceMarkdown();
    if (docs_out->empty()) {
      std::cout << text;
      return;
    }
    WriteFileAtomically(*docs_out, text);
  });

  auto* kinds =
      app->add_subcommand("kinds", "list the experiment kinds of this build and their steps");
  kinds->callback([registry] {
    for (const ExperimentKind& k : registry->kinds())
      std::cout << k.tag << (k.tag_is_prefix ? "*" : "") << "\t" << k.summary
                << "\tsteps:" << (k.train ? " train" : "") << (k.export_run ? " export" : "")
                << (k.evaluate ? " eval" : "") << (k.bench ? " bench" : "")
                << (k.resumable ? " (resumable)" : "") << "\n";
  });
}

}  // namespace foresight::app
