#pragma once
/// Sub-command registration of the `foresight` CLI (each file adds its own sub-commands).

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "training/experiment.h"

namespace foresight::app {

/// train, export, eval, docs config, kinds: the same commands for every experiment kind.
void AddExperimentCommands(CLI::App* app, std::shared_ptr<const ExperimentRegistry> registry);
void AddDataCommands(CLI::App* app);
void AddBenchCommands(CLI::App* app);
void AddMapCommands(CLI::App* app);        // map fuse, map info
void AddBenchMapCommand(CLI::App* bench);  // bench map (under `bench`)
/// `bench directional` (under `bench`; needs LibTorch for the comparison).
void AddBenchDirectionalCommand(CLI::App* bench);
/// `bench diffeo --artifact FILE` (under `bench`; needs LibTorch for the comparison).
void AddBenchDiffeoCommand(CLI::App* bench);
void AddBenchOtnetCommand(CLI::App* bench);
/// `navigate CONFIG --run-dir DIR [--episodes N]` (SPAN and baselines in a crowd scenario).
void AddNavigateCommand(CLI::App* app);
/// `plan CONFIG [--problems A-B] --run-dir DIR` (GFCS, fabric and planners on manipulation
/// problems).
void AddPlanCommand(CLI::App* app);
/// `bench fabric [--json]` (under `bench`): FK, fabric step and rollout times, KDL alongside.
void AddBenchFabricCommand(CLI::App* bench);

}  // namespace foresight::app
