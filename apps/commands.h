#pragma once
/// Sub-command registration of the `foresight` CLI (each file adds its own sub-commands).

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "training/experiment.h"

namespace foresight::app {

/// train, export, eval, bench, docs config, kinds: the same commands for every experiment kind.
void AddExperimentCommands(CLI::App* app, std::shared_ptr<const ExperimentRegistry> registry);
void AddDataCommands(CLI::App* app);
void AddMapCommands(CLI::App* app);  // map fuse, map info
/// `navigate CONFIG --run-dir DIR [--episodes N]` (SPAN and baselines in a crowd scenario).
void AddNavigateCommand(CLI::App* app);
/// `plan CONFIG [--problems A-B] --run-dir DIR` (GFCS, fabric and planners on manipulation
/// problems).
void AddPlanCommand(CLI::App* app);

}  // namespace foresight::app
