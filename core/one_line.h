#pragma once
/// Quoting text from a file in a one-line Error.

#include <string>

namespace foresight {

/// `text` with control characters escaped (a newline becomes the two characters '\' 'n', other
/// control characters but tab become '\xNN'), so that file contents and third-party messages
/// (yaml-cpp's) quoted in an Error keep it on one line.
inline std::string OneLine(const std::string& text) {
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  for (const char ch : text) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == '\n') {
      out += "\\n";
    } else if ((u < 0x20 && ch != '\t') || u == 0x7f) {
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

}  // namespace foresight
