// `foresight plan CONFIG [overrides] [--problems A-B] [--run-dir DIR]`: GFCS, the geometric fabric
// and the OMPL planners over a family of manipulation problems (thesis ch 9).

#include <filesystem>
#include <iomanip>
#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "embedded_manipulation_config.h"
#include "training/manipulation/config.h"
#include "training/manipulation/plan.h"
#include "training/run_dir.h"

namespace foresight::app {
namespace fs = std::filesystem;

namespace {
struct PlanArgs {
  std::string config, run_dir, problems;
  std::vector<std::string> overrides;
};

std::string Format(const manipulation::Stat& s) {
  if (!s.mean) return "-";
  std::ostringstream os;
  os << std::fixed << std::setprecision(2) << *s.mean;
  if (s.std) os << "+-" << *s.std;
  return os.str();
}

void PrintTable(const manipulation::PlanReport& report) {
  std::cout << std::left << std::setw(18) << "method" << std::right << std::setw(9) << "success"
            << std::setw(14) << "EE length" << std::setw(14) << "C-space len" << std::setw(14)
            << "time s" << std::setw(14) << "EE-LDJ" << std::setw(14) << "C-space LDJ"
            << "\n";
  for (const manipulation::PlanMethodResult& m : report.methods) {
    const manipulation::MetricSummary& s = m.summary;
    std::cout << std::left << std::setw(18) << m.method << std::right << std::setw(8) << std::fixed
              << std::setprecision(0) << 100 * s.success_rate << "%" << std::setw(14)
              << Format(s.ee_length) << std::setw(14) << Format(s.cspace_length) << std::setw(14)
              << Format(s.time_s) << std::setw(14) << Format(s.ee_ldj) << std::setw(14)
              << Format(s.cspace_ldj) << "\n";
  }
  std::cout << std::defaultfloat;
}

/// "A-B" or "A" -> first, last.
std::pair<int, int> ParseRange(const std::string& text) {
  const auto dash = text.find('-');
  try {
    const int a = std::stoi(text.substr(0, dash));
    const int b = dash == std::string::npos ? a : std::stoi(text.substr(dash + 1));
    FS_THROW_UNLESS(a >= 1 && a <= b, "--problems: '", text, "': expected A-B with 1 <= A <= B");
    return {a, b};
  } catch (const std::logic_error&) {
    Fail("--problems: '", text, "': expected A-B, e.g. 51-75");
  }
}
}  // namespace

void AddPlanCommand(CLI::App* app) {
  auto args = std::make_shared<PlanArgs>();
  auto* plan = app->add_subcommand(
      "plan", "run GFCS, the geometric fabric and OMPL planners over manipulation problems");
  plan->add_option("config", args->config,
                   "manipulation config (configs/manipulation/*.yaml), or 'default' for the "
                   "embedded synthetic quickstart (configs/manipulation/synthetic.yaml)")
      ->required();
  plan->add_option("overrides", args->overrides, "key.path=value overrides of the config");
  plan->add_option("--problems", args->problems, "problem numbers A-B (default: the config's)");
  plan->add_option("--run-dir", args->run_dir, "run directory (default runs/plan_<config name>)");
  plan->callback([args] {
    const bool embedded = args->config == "default";
    std::vector<std::string> overrides = args->overrides;
    if (!args->problems.empty()) {
      const auto [first, last] = ParseRange(args->problems);
      overrides.push_back("problems.first=" + std::to_string(first));
      overrides.push_back("problems.last=" + std::to_string(last));
    }
    const manipulation::ExperimentConfig c =
        embedded
            ? config::ExperimentConfigFromYaml<manipulation::ExperimentConfig>(
                  kEmbeddedManipulationConfig, "<embedded configs/manipulation/synthetic.yaml>",
                  overrides)
            : config::LoadExperimentConfig<manipulation::ExperimentConfig>(args->config, overrides);
    const std::string out =
        !args->run_dir.empty() ? args->run_dir
                               : "runs/plan_" + (embedded ? std::string("synthetic")
                                                          : fs::path(args->config).stem().string());
    StartRunDirectory(out, config::ToYaml(c), false, manipulation::kRunRules);
    std::cout << "planning "
              << (c.problems.source == manipulation::ProblemSource::kSynthetic
                      ? std::string("synthetic scenes")
                      : c.problems.family)
              << " with " << c.methods.size() << " methods -> " << out << "\n";
    const manipulation::PlanReport report = manipulation::RunPlanExperiment(c, out);
    PrintTable(report);
    if (!report.invalid_problems.empty())
      std::cout
          << report.invalid_problems.size()
          << " problem(s) skipped: start or goal invalid for this robot model (see log.txt)\n";
    if (c.reactivity.enabled)
      std::cout << "reactivity: " << report.reactivity_successes << " of "
                << report.reactivity_trials << " re-runs with added obstacles reached the goal\n";
    std::cout << "wrote " << out << "/summary.json, problems.csv"
              << (c.plot_problems > 0 ? ", ee_paths.png" : "") << "\n";
  });
}

}  // namespace foresight::app
