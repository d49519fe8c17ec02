#pragma once
/// Whole-string number parsing shared by the config reader and the dataset readers.

#include <optional>
#include <string>

namespace foresight {

/// The number that `text` spells exactly (no trailing characters), or nothing. May be inf/nan.
inline std::optional<double> ParseDouble(const std::string& text) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used == 0 || used != text.size()) return std::nullopt;
  return v;
}

/// The integer that `text` spells exactly, or nothing.
inline std::optional<long long> ParseInteger(const std::string& text) {
  std::size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used == 0 || used != text.size()) return std::nullopt;
  return v;
}

}  // namespace foresight
