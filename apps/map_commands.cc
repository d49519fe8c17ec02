// `foresight map fuse | info` and the occupancy branch of `foresight train`.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>

#include "apps/commands.h"
#include "core/config.h"
#include "core/error.h"
#include "inference/engine/artifact.h"
#include "inference/mapping/fusion.h"
#include "inference/mapping/hinge_map.h"
#include "inference/mapping/occupancy_map.h"
#include "training/occupancy/pipeline.h"

namespace foresight::app {
namespace fs = std::filesystem;

namespace {
struct FuseArgs {
  std::vector<std::string> inputs;
  std::string output, base;
  double threshold = occupancy::FusionOptions{}.variance_threshold;
};

/// Whether two files hold the same bytes (a copied artifact under another name).
bool SameBytes(const std::string& a, const std::string& b) {
  if (fs::file_size(a) != fs::file_size(b)) return false;
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  return std::equal(std::istreambuf_iterator<char>(fa), std::istreambuf_iterator<char>(),
                    std::istreambuf_iterator<char>(fb));
}
}  // namespace

void AddMapCommands(CLI::App* app) {
  auto* map = app->add_subcommand("map", "occupancy-map tools (fusion, inspection)");
  map->require_subcommand(1);

  auto args = std::make_shared<FuseArgs>();
  auto* fuse =
      map->add_subcommand("fuse", "fuse Fast-BHM artifacts of a shared feature grid into one");
  fuse->add_option("maps", args->inputs, "Fast-BHM artifacts (model.h5 of each robot)")
      ->required()
      ->check(CLI::ExistingFile);
  fuse->add_option("-o,--output", args->output, "fused artifact to write")->required();
  fuse->add_option(
          "--base", args->base,
          "last global map the inputs were copied from (repeated fusion: merge their increments)")
      ->check(CLI::ExistingFile);
  fuse->add_option("--variance-threshold", args->threshold,
                   "local weight estimates with a variance at or above this are left out")
      ->check(CLI::PositiveNumber);
  fuse->callback([args] {
    FS_THROW_UNLESS(std::isfinite(args->threshold) && args->threshold > 0,
                    "--variance-threshold: ", args->threshold, " is not a finite positive number");
    for (std::size_t i = 0; i < args->inputs.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        FS_THROW_UNLESS(!fs::equivalent(args->inputs[i], args->inputs[j]), args->inputs[i],
                        ": the same map is given twice (as input ", j + 1, " and ", i + 1,
                        "); fusing a map with itself counts its evidence twice");
    for (std::size_t i = 0; i < args->inputs.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        // Copies of --base itself are robots that saw nothing new: their increments are zero.
        FS_THROW_UNLESS(!SameBytes(args->inputs[i], args->inputs[j]) ||
                            (!args->base.empty() && SameBytes(args->inputs[i], args->base)),
                        args->inputs[i], ": holds the same bytes as input ", j + 1, " (",
                        args->inputs[j],
                        "), a copy of one map; fusing a map with itself counts its evidence twice");
    std::vector<std::string> read = args->inputs;
    if (!args->base.empty()) read.push_back(args->base);
    for (const std::string& in : read)
      FS_THROW_UNLESS(!fs::exists(args->output) || !fs::equivalent(args->output, in), args->output,
                      ": the output is also an input (", in,
                      "); write the fused map to a new file");
    std::vector<occupancy::HingeMap> maps;
    for (const auto& p : args->inputs) maps.push_back(occupancy::HingeMap::Load(p));
    std::vector<const occupancy::HingeMap*> ptrs;
    for (const auto& m : maps) ptrs.push_back(&m);
    std::unique_ptr<occupancy::HingeMap> base;
    if (!args->base.empty())
      base = std::make_unique<occupancy::HingeMap>(occupancy::HingeMap::Load(args->base));
    occupancy::FusionOptions options;
    options.variance_threshold = args->threshold;
    const occupancy::HingeMap fused = occupancy::FuseMaps(ptrs, args->inputs, options, base.get());
    // The fused map carries the first input's config (same grid and prior by construction).
    const Artifact first = Artifact::Open(args->inputs[0], "");
    fused.Save(args->output, first.config_yaml(), first.seed());
    std::cout << "fused " << maps.size() << " maps" << (base ? " (increments over --base)" : "")
              << " into " << args->output << " (" << fs::file_size(args->output) << " bytes)\n";
  });

  auto path = std::make_shared<std::string>();
  auto* info =
      map->add_subcommand("info", "print an occupancy-map artifact's type, extent and size");
  info->add_option("artifact", *path, "map artifact")->required()->check(CLI::ExistingFile);
  info->callback([path] {
    const auto m = occupancy::LoadMap(*path);
    const Eigen::Vector4d e = m->Extent();
    std::cout << "{\"model_type\": \"" << m->model_type() << "\", \"extent\": [" << e[0] << ", "
              << e[1] << ", " << e[2] << ", " << e[3] << "], \"bytes\": " << fs::file_size(*path)
              << "}\n";
  });
}

}  // namespace foresight::app
