// `foresight map fuse | info` and the occupancy branch of `foresight train`.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/commands.h"
#include "core/config.h"
#include "core/error.h"
#include "inference/engine/artifact.h"
#include "inference/mapping/fusion.h"
#include "inference/mapping/hinge_map.h"
#include "inference/mapping/occupancy_map.h"
#include "training/occupancy_pipeline.h"

namespace foresight::app {
namespace fs = std::filesystem;

bool IsOccupancyConfig(const std::string& path) {
  if (path.empty() || path == "default") return false;
  const YAML::Node root = config::LoadYamlFile(path);
  if (!root.IsMap() || !root["model"] || !root["model"].IsScalar()) return false;
  return root["model"].as<std::string>().rfind("occupancy.", 0) == 0;
}

void TrainOccupancy(const std::string& config_path, const std::vector<std::string>& overrides,
                    const std::string& run_dir, bool resume) {
  FS_THROW_UNLESS(!resume, "--resume: occupancy maps train in one pass (seconds); run again instead");
  const OccupancyExperimentConfig c = LoadOccupancyConfig(config_path, overrides);
  for (const char* f : {"model.h5", "eval.json"})
    FS_THROW_UNLESS(!fs::exists(fs::path(run_dir) / f), run_dir, ": already holds ", f,
                    " of an earlier run; use a new or empty --run-dir");
  std::cout << RunOccupancyExperiment(c, config::ToYaml(c), run_dir);
  std::cout << "wrote " << run_dir << "/model.h5, eval.json and plots/map.png\n";
}

void EvalOccupancy(const std::string& config_path, const std::vector<std::string>& overrides,
                   const std::string& run_dir) {
  const OccupancyExperimentConfig c = LoadOccupancyConfig(config_path, overrides);
  const std::string artifact = run_dir + "/model.h5";
  FS_THROW_UNLESS(fs::exists(artifact), artifact, ": not found (train the map first)");
  const auto map = LoadOccupancyMap(artifact);
  const OccupancyData data = LoadOccupancyData(c);
  const BinaryMetrics m = EvaluateMap(*map, data.test);
  std::cout << "{\"model_type\": \"" << map->model_type() << "\", \"test_points\": " << data.test.size()
            << ", \"auc\": " << m.auc << ", \"precision\": " << m.precision << ", \"recall\": " << m.recall
            << ", \"artifact_bytes\": " << fs::file_size(artifact) << "}\n";
}

namespace {
struct FuseArgs {
  std::vector<std::string> inputs;
  std::string output, base;
  double threshold = FusionOptions{}.variance_threshold;
};
}  // namespace

void AddMapCommands(CLI::App* app) {
  auto* map = app->add_subcommand("map", "occupancy-map tools (fusion, inspection)");
  map->require_subcommand(1);

  auto args = std::make_shared<FuseArgs>();
  auto* fuse = map->add_subcommand("fuse", "fuse Fast-BHM artifacts of a shared feature grid into one");
  fuse->add_option("maps", args->inputs, "Fast-BHM artifacts (model.h5 of each robot)")->required()->check(CLI::ExistingFile);
  fuse->add_option("-o,--output", args->output, "fused artifact to write")->required();
  fuse->add_option("--base", args->base,
                   "last global map the inputs were copied from (repeated fusion: merge their increments)")
      ->check(CLI::ExistingFile);
  fuse->add_option("--variance-threshold", args->threshold,
                   "local weight estimates with a variance at or above this are left out")
      ->check(CLI::PositiveNumber);
  fuse->callback([args] {
    std::vector<HingeMap> maps;
    for (const auto& p : args->inputs) maps.push_back(HingeMap::Load(p));
    std::vector<const HingeMap*> ptrs;
    for (const auto& m : maps) ptrs.push_back(&m);
    std::unique_ptr<HingeMap> base;
    if (!args->base.empty()) base = std::make_unique<HingeMap>(HingeMap::Load(args->base));
    FusionOptions options;
    options.variance_threshold = args->threshold;
    const HingeMap fused = FuseMaps(ptrs, args->inputs, options, base.get());
    // The fused map carries the first input's config (same grid and prior by construction).
    const Artifact first = Artifact::Open(args->inputs[0], "");
    fused.Save(args->output, first.config_yaml(), first.seed());
    std::cout << "fused " << maps.size() << " maps" << (base ? " (increments over --base)" : "") << " into "
              << args->output << " (" << fs::file_size(args->output) << " bytes)\n";
  });

  auto path = std::make_shared<std::string>();
  auto* info = map->add_subcommand("info", "print an occupancy-map artifact's type, extent and size");
  info->add_option("artifact", *path, "map artifact")->required()->check(CLI::ExistingFile);
  info->callback([path] {
    const auto m = LoadOccupancyMap(*path);
    const Eigen::Vector4d e = m->Extent();
    std::cout << "{\"model_type\": \"" << m->model_type() << "\", \"extent\": [" << e[0] << ", " << e[1] << ", "
              << e[2] << ", " << e[3] << "], \"bytes\": " << fs::file_size(*path) << "}\n";
  });
}

void AddOccupancyOnlyTrainCommand(CLI::App* app) {
  struct Args {
    std::string config, run_dir;
    std::vector<std::string> overrides;
  };
  auto a = std::make_shared<Args>();
  auto* train = app->add_subcommand("train", "train an occupancy map from a YAML config (this build has no LibTorch)");
  train->add_option("config", a->config, "config file (model: occupancy.*)")->required();
  train->add_option("overrides", a->overrides, "key.path=value overrides of the config");
  train->add_option("--run-dir", a->run_dir, "run directory (default runs/<config name>)");
  train->callback([a] {
    FS_THROW_UNLESS(IsOccupancyConfig(a->config), a->config,
                    ": this build has no LibTorch and trains occupancy maps (model: occupancy.*) only");
    TrainOccupancy(a->config, a->overrides,
                   a->run_dir.empty() ? "runs/" + fs::path(a->config).stem().string() : a->run_dir, false);
  });
}

}  // namespace foresight::app
