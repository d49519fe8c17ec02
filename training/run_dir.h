#pragma once
/// The one run directory every command that writes results uses (train, eval, navigate, the
/// experiment binaries): the resolved config.yaml it was started with, log.txt, and its outputs.
/// Torch-free.

#include <string>
#include <vector>

namespace foresight {

/// What shows that a directory already holds a run of a kind, and whether it can be continued.
struct RunDirectoryRules {
  /// Files or folders (relative to the run directory) an earlier run leaves; a folder holding
  /// nothing but temporary files (NAME.tmp) counts as absent (a run killed before its first
  /// checkpoint left nothing to continue).
  std::vector<std::string> markers;
  bool resumable = false;  ///< the kind continues a killed run with --resume
};

/// Creates `run_dir` and logs to run_dir/log.txt. A fresh start refuses a directory holding any
/// marker of `rules` (naming it) and writes `resolved_yaml` to run_dir/config.yaml; a resume
/// (only for resumable kinds) requires that file to hold the same text. Errors name the directory.
void StartRunDirectory(const std::string& run_dir, const std::string& resolved_yaml, bool resume,
                       const RunDirectoryRules& rules);

/// The whole text of a file ("" when it cannot be read).
std::string ReadText(const std::string& path);

}  // namespace foresight
