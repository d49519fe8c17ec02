#pragma once
/// Sub-command registration of the `foresight` CLI (each file adds its own sub-commands).

#include <CLI/CLI.hpp>

namespace foresight::app {

void AddDataCommands(CLI::App* app);
void AddBenchCommands(CLI::App* app);
void AddTrainCommands(CLI::App* app);  // train, export, eval, docs (needs LibTorch)

}  // namespace foresight::app
