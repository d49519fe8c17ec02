#include "core/log.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <mutex>

namespace foresight::log {
namespace {
struct Sink {
  std::mutex mutex;
  std::ofstream file;
  Level stderr_level = Level::kInfo;
};
Sink& GetSink() {
  static Sink sink;
  return sink;
}
const char* Tag(Level l) {
  switch (l) {
    case Level::kDebug:
      return "debug";
    case Level::kInfo:
      return "info";
    case Level::kWarn:
      return "warn";
    case Level::kError:
      return "error";
  }
  return "";
}
}  // namespace

void SetFile(const std::string& path) {
  Sink& s = GetSink();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (s.file.is_open()) s.file.close();
  if (!path.empty()) s.file.open(path, std::ios::app);
}

void SetStderrLevel(Level level) { GetSink().stderr_level = level; }

void Write(Level level, const std::string& message) {
  Sink& s = GetSink();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (level >= s.stderr_level) std::cerr << "[" << Tag(level) << "] " << message << "\n";
  if (s.file.is_open() && level >= Level::kInfo) {
    const std::time_t now = std::time(nullptr);
    char stamp[32];
    std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S", std::localtime(&now));
    s.file << stamp << " [" << Tag(level) << "] " << message << "\n";
    s.file.flush();
  }
}

}  // namespace foresight::log
