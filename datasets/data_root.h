#pragma once
/// Where real data files are found: a relative name resolves against the configured root, else
/// $FORESIGHT_DATA, else ../shared/data relative to the working directory.

#include <cstdlib>
#include <filesystem>
#include <string>

namespace foresight {

inline std::string ResolveDataFile(const std::string& root, const std::string& file) {
  if (std::filesystem::path(file).is_absolute()) return file;
  std::string r = root;
  if (r.empty()) {
    const char* env = std::getenv("FORESIGHT_DATA");
    r = (env && *env) ? env : "../shared/data";
  }
  return (std::filesystem::path(r) / file).string();
}

}  // namespace foresight
