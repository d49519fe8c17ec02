#pragma once
/// A small ordered JSON object writer for eval.json files: keys keep their insertion order,
/// non-finite numbers are written as null (JSON has no NaN/inf), strings are escaped.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace foresight {

class JsonObject {
 public:
  JsonObject& Set(const std::string& key, double value);
  JsonObject& Set(const std::string& key, int value) {
    return Set(key, static_cast<std::int64_t>(value));
  }
  JsonObject& Set(const std::string& key, std::int64_t value);
  JsonObject& Set(const std::string& key, bool value);
  JsonObject& Set(const std::string& key, const std::string& value);
  JsonObject& Set(const std::string& key, const char* value) {
    return Set(key, std::string(value));
  }
  JsonObject& Set(const std::string& key, const JsonObject& value);
  /// An array of numbers (non-finite as null).
  JsonObject& Set(const std::string& key, const std::vector<double>& values);
  bool empty() const { return entries_.empty(); }
  /// Pretty-printed with two spaces per level; ends without a newline.
  std::string Dump(int indent = 0) const;

 private:
  struct Entry {
    std::string key;
    std::string scalar;                  ///< rendered value, or empty for an object
    std::shared_ptr<JsonObject> object;  ///< nested object
  };
  void Put(const std::string& key, std::string scalar, std::shared_ptr<JsonObject> object);
  std::vector<Entry> entries_;
};

/// A JSON number (shortest round-trip form with up to 10 significant digits) or null.
std::string JsonNumber(double v);
/// A quoted, escaped JSON string.
std::string JsonString(const std::string& s);

}  // namespace foresight
