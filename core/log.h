#pragma once
/// Minimal leveled logging to stderr and, when a run directory is open, to its log file.

#include <string>

#include "core/error.h"

namespace foresight::log {

enum class Level { kDebug, kInfo, kWarn, kError };

/// Also append every message to `path` (the run's log.txt); empty closes it.
void SetFile(const std::string& path);
/// Messages below `level` are not printed to stderr (the file gets kInfo and above).
void SetStderrLevel(Level level);
void Write(Level level, const std::string& message);

template <typename... Args>
void Info(const Args&... args) {
  Write(Level::kInfo, foresight::internal::Concat(args...));
}
template <typename... Args>
void Warn(const Args&... args) {
  Write(Level::kWarn, foresight::internal::Concat(args...));
}
template <typename... Args>
void Debug(const Args&... args) {
  Write(Level::kDebug, foresight::internal::Concat(args...));
}

}  // namespace foresight::log
