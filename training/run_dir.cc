#include "training/run_dir.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"

namespace foresight {
namespace fs = std::filesystem;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

namespace {
/// A folder holds something an earlier run completed: any entry but a temporary file (NAME.tmp),
/// which a run killed while writing leaves behind and which never replaced a complete file.
bool HoldsCompleteFile(const fs::path& dir) {
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    if (e.path().extension() != ".tmp") return true;
  return false;
}
}  // namespace

void StartRunDirectory(const std::string& run_dir, const std::string& resolved_yaml, bool resume,
                       const RunDirectoryRules& rules) {
  FS_THROW_UNLESS(!resume || rules.resumable,
                  "--resume: this kind runs in one pass and cannot be continued; "
                  "run it again into a new or empty --run-dir");
  const std::string config_path = run_dir + "/config.yaml";
  if (resume) {
    FS_THROW_UNLESS(fs::exists(config_path), run_dir, ": no config.yaml to resume from");
    FS_THROW_UNLESS(ReadText(config_path) == resolved_yaml, config_path,
                    ": the resolved config differs from the one this run started with; "
                    "resume with the same config and overrides");
  } else {
    for (const std::string& marker : rules.markers) {
      const fs::path p = fs::path(run_dir) / marker;
      const bool present = fs::is_directory(p) ? HoldsCompleteFile(p) : fs::exists(p);
      FS_THROW_UNLESS(!present, run_dir, ": already holds a run (", marker, "); ",
                      rules.resumable ? "continue it with --resume, or " : "",
                      "use a new or empty --run-dir");
    }
    fs::create_directories(run_dir);
    WriteFileAtomically(config_path, resolved_yaml);
  }
  log::SetFile(run_dir + "/log.txt");
}

}  // namespace foresight
