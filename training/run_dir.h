#pragma once
/// The start of every trained run: the run directory holds the resolved config it was started with
/// and the log. Torch-free.

#include <string>

namespace foresight {

/// Creates `run_dir`; a fresh start writes `resolved_yaml` to run_dir/config.yaml, a resume requires
/// that file to hold the same text (an Error otherwise). Then logs to run_dir/log.txt.
void StartRunDirectory(const std::string& run_dir, const std::string& resolved_yaml, bool resume);

/// The whole text of a file ("" when it cannot be read).
std::string ReadText(const std::string& path);

}  // namespace foresight
