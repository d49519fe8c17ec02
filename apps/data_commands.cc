// `foresight data convert | generate | info`

#include <cmath>
#include <iostream>

#include "apps/commands.h"
#include "core/config.h"
#include "core/error.h"
#include "datasets/eth_ucy.h"
#include "datasets/synthetic_pedestrians.h"
#include "datasets/track_store.h"

namespace foresight::app {

void AddDataCommands(CLI::App* app) {
  auto* data = app->add_subcommand(
      "data", "convert real datasets and generate synthetic ones (HDF5 track store)");
  data->require_subcommand(1);

  struct ConvertArgs {
    std::string format = "eth_ucy", output;
    std::vector<std::string> inputs;
    double seconds_per_step = 0.4;
  };
  auto convert_args = std::make_shared<ConvertArgs>();
  auto* convert = data->add_subcommand("convert", "convert text tracks to one HDF5 track store");
  convert->add_option("inputs", convert_args->inputs, "input files")->required();
  convert->add_option("-o,--output", convert_args->output, "output .h5")->required();
  convert->add_option("--format", convert_args->format, "input format")
      ->check(CLI::IsMember({"eth_ucy"}));
  convert
      ->add_option("--seconds-per-step", convert_args->seconds_per_step, "seconds per frame step")
      ->check(CLI::PositiveNumber);
  convert->callback([convert_args] {
    // CLI::PositiveNumber lets nan through (nan <= 0 is false).
    FS_THROW_UNLESS(std::isfinite(convert_args->seconds_per_step),
                    "--seconds-per-step: ", convert_args->seconds_per_step,
                    " is not a finite number > 0");
    TrackSet all;
    all.seconds_per_step = convert_args->seconds_per_step;
    for (const auto& in : convert_args->inputs) {
      TrackSet part = ReadEthUcy(in, convert_args->seconds_per_step);
      all.source += (all.source.empty() ? "" : ",") + in;
      for (auto& t : part.tracks) all.tracks.push_back(std::move(t));
    }
    WriteTrackStore(convert_args->output, all);
    std::cout << convert_args->output << ": " << all.tracks.size() << " tracks, " << all.NumPoints()
              << " points\n";
  });

  struct GenerateArgs {
    std::string output, config;
    std::vector<std::string> overrides;
  };
  auto gen_args = std::make_shared<GenerateArgs>();
  auto* gen = data->add_subcommand("generate", "generate synthetic pedestrian tracks");
  gen->add_option("overrides", gen_args->overrides,
                  "generator settings key=value (see docs/config_reference.md, data.synthetic)");
  gen->add_option("-o,--output", gen_args->output, "output .h5")->required();
  gen->add_option("--config", gen_args->config, "YAML file of generator settings");
  gen->callback([gen_args] {
    const auto cfg = gen_args->config.empty() ? config::FromYaml<SyntheticPedestrianConfig>(
                                                    YAML::Node(), "<defaults>", gen_args->overrides)
                                              : config::LoadFile<SyntheticPedestrianConfig>(
                                                    gen_args->config, gen_args->overrides);
    const TrackSet set = GenerateSyntheticPedestrians(cfg);
    WriteTrackStore(gen_args->output, set);
    std::cout << gen_args->output << ": " << set.tracks.size() << " tracks, " << set.NumPoints()
              << " points\n";
  });

  auto info_path = std::make_shared<std::string>();
  auto* info = data->add_subcommand("info", "summarise a track store");
  info->add_option("file", *info_path, "track store .h5")->required();
  info->callback([info_path] {
    const TrackSet set = ReadTrackStore(*info_path);
    std::cout << *info_path << ": source " << set.source << ", " << set.tracks.size() << " tracks, "
              << set.NumPoints() << " points, " << set.seconds_per_step << " s per step\n";
  });
}

}  // namespace foresight::app
