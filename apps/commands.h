#pragma once
/// Sub-command registration of the `foresight` CLI (each file adds its own sub-commands).

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace foresight::app {

void AddDataCommands(CLI::App* app);
void AddBenchCommands(CLI::App* app);
void AddTrainCommands(CLI::App* app);  // train, export, eval, docs (needs LibTorch)
void AddMapCommands(CLI::App* app);    // map fuse, map info
void AddBenchMapCommand(CLI::App* bench);  // bench map (under `bench`)
/// `train` for builds without LibTorch: occupancy configs only.
void AddOccupancyOnlyTrainCommand(CLI::App* app);

/// True when the YAML file's `model` is `directional` (continuous directional maps; needs LibTorch).
bool IsDirectionalConfig(const std::string& path);
/// `bench directional` (under `bench`; needs LibTorch for the comparison).
void AddBenchDirectionalCommand(CLI::App* bench);
/// True when the YAML file's `model` is occupancy.* (so `train` runs the occupancy pipeline).
bool IsOccupancyConfig(const std::string& path);
/// Evaluates run_dir/model.h5 (any occupancy map) on the config's test scans; prints JSON.
void EvalOccupancy(const std::string& config_path, const std::vector<std::string>& overrides,
                   const std::string& run_dir);
/// Trains, exports and evaluates an occupancy map into run_dir (refuses a used run_dir).
void TrainOccupancy(const std::string& config_path, const std::vector<std::string>& overrides,
                    const std::string& run_dir, bool resume);

/// `navigate CONFIG --out DIR [--episodes N]` (SPAN and baselines in a crowd scenario).
void AddNavigateCommand(CLI::App* app);

}  // namespace foresight::app

