// `foresight navigate CONFIG --out DIR [--episodes N]`: SPAN and the baselines in a crowd scenario.

#include <filesystem>
#include <iomanip>
#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/log.h"
#include "embedded_navigation_config.h"
#include "training/navigation/config.h"
#include "training/navigation/run.h"
#ifdef FORESIGHT_WITH_TORCH
#include "embedded_navigation_predictor_config.h"
#include "training/navigation/predictor.h"
#endif

namespace foresight::app {
namespace fs = std::filesystem;

namespace {
struct NavigateArgs {
  std::string config, run_dir;
  std::vector<std::string> overrides;
  int episodes = 0;
};

void PrintTable(const std::vector<nav::MethodSummary>& rows) {
  std::cout << std::left << std::setw(12) << "method" << std::right << std::setw(9) << "success"
            << std::setw(9) << "no-coll" << std::setw(9) << "TTG s" << std::setw(9) << "DOC s"
            << std::setw(10) << "min gap" << std::setw(11) << "cycle med" << std::setw(11)
            << "cycle p99" << std::setw(9) << "failed"
            << "\n";
  std::cout << std::fixed << std::setprecision(2);
  for (const nav::MethodSummary& m : rows)
    std::cout << std::left << std::setw(12) << m.method << std::right << std::setw(9)
              << m.success_rate << std::setw(9) << m.collision_free_rate << std::setw(9)
              << m.ttg_mean << std::setw(9) << m.doc_mean << std::setw(10) << m.min_clearance
              << std::setw(8) << m.cycle_ms_median << " ms" << std::setw(8) << m.cycle_ms_p99
              << " ms" << std::setw(9) << m.solve_failures << "\n";
  std::cout << std::defaultfloat;
}
}  // namespace

void AddNavigateCommand(CLI::App* app) {
  auto args = std::make_shared<NavigateArgs>();
  auto* nav = app->add_subcommand(
      "navigate", "run SPAN and the reactive and CL-RRT* baselines through a crowd scenario");
  nav->add_option("config", args->config,
                  "navigation config (configs/navigation/*.yaml), or 'default' for the embedded "
                  "configs/navigation/sim1.yaml")
      ->required();
  nav->add_option("overrides", args->overrides, "key.path=value overrides of the config");
  nav->add_option("--run-dir", args->run_dir,
                  "run directory (default runs/navigate_<config name>)");
  nav->add_option("--episodes", args->episodes, "episodes per method (default: the config's)")
      ->check(CLI::Range(1, 100000));
  nav->callback([args] {
    const bool embedded = args->config == "default";
    const nav::ExperimentConfig c =
        embedded
            ? config::ExperimentConfigFromYaml<nav::ExperimentConfig>(
                  kEmbeddedNavigationConfig, "<embedded configs/navigation/sim1.yaml>",
                  args->overrides)
            : config::LoadExperimentConfig<nav::ExperimentConfig>(args->config, args->overrides);
    const std::string out =
        !args->run_dir.empty()
            ? args->run_dir
            : "runs/navigate_" +
                  (embedded ? std::string("sim1") : fs::path(args->config).stem().string());
    StartRunDirectory(out, config::ToYaml(c), false, nav::kRunRules);
    const bool needs_predictor = c.Uses(nav::Method::kSpan);
#ifdef FORESIGHT_WITH_TORCH
    if (needs_predictor) {
      // Trains a missing predictor; checks one it trained before against the config.
      nav::EnsurePredictor(c, kEmbeddedNavigationPredictorConfig);
      log::SetFile(out + "/log.txt");  // the predictor's training logged into its own run directory
    }
#else
    if (needs_predictor && !fs::exists(c.predictor.artifact))
      Fail("predictor.artifact: ", c.predictor.artifact,
           " not found; this build has no LibTorch to train it (train it with a LibTorch build "
           "first)");
#endif
    const int episodes = args->episodes > 0 ? args->episodes : c.episodes;
    std::cout << "navigating " << c.scenario.name << ": " << episodes << " episodes x "
              << c.methods.size() << " methods -> " << out << "\n";
    const std::vector<nav::MethodSummary> rows = nav::RunNavigation(c, out, episodes);
    PrintTable(rows);
    std::cout << "wrote " << out << "/summary.json, episodes.csv, paths.png"
              << (c.video.enabled ? ", episode.avi" : "") << "\n";
  });
}

}  // namespace foresight::app
