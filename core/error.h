#pragma once
/// Errors for bad user input: one exception type whose message names what was wrong and where.
/// Internal invariants use assert(); expected outcomes (non-finite loss, early stop) are values.

#include <sstream>
#include <stdexcept>
#include <string>

namespace foresight {

/// Thrown for bad input (files, configs, artifacts, arguments). The message is one line.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

namespace internal {
template <typename... Args>
std::string Concat(const Args&... args) {
  std::ostringstream os;
  (os << ... << args);
  return os.str();
}
}  // namespace internal

/// Throws foresight::Error with the concatenation of the arguments.
template <typename... Args>
[[noreturn]] void Fail(const Args&... args) {
  throw Error(internal::Concat(args...));
}

}  // namespace foresight

/// Throws foresight::Error(message...) unless `cond` holds. Use for user input, not invariants.
#define FS_THROW_UNLESS(cond, ...)               \
  do {                                           \
    if (!(cond)) ::foresight::Fail(__VA_ARGS__); \
  } while (0)
