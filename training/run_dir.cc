#include "training/run_dir.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/log.h"

namespace foresight {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void StartRunDirectory(const std::string& run_dir, const std::string& resolved_yaml, bool resume) {
  std::filesystem::create_directories(run_dir);
  const std::string config_path = run_dir + "/config.yaml";
  if (resume) {
    FS_THROW_UNLESS(std::filesystem::exists(config_path), run_dir, ": no config.yaml to resume from");
    FS_THROW_UNLESS(ReadText(config_path) == resolved_yaml, config_path,
                    ": the resolved config differs from the one this run started with; "
                    "resume with the same config and overrides");
  } else {
    std::ofstream(config_path) << resolved_yaml;
  }
  log::SetFile(run_dir + "/log.txt");
}

}  // namespace foresight
