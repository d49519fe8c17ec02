#include "core/json.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace foresight {

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return buf;
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    switch (ch) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", static_cast<unsigned>(ch));
          out += buf;
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

void JsonObject::Put(const std::string& key, std::string scalar,
                     std::shared_ptr<JsonObject> object) {
  for (Entry& e : entries_)
    if (e.key == key) {
      e.scalar = std::move(scalar);
      e.object = std::move(object);
      return;
    }
  entries_.push_back({key, std::move(scalar), std::move(object)});
}

JsonObject& JsonObject::Set(const std::string& key, double value) {
  Put(key, JsonNumber(value), nullptr);
  return *this;
}
JsonObject& JsonObject::Set(const std::string& key, std::int64_t value) {
  Put(key, std::to_string(value), nullptr);
  return *this;
}
JsonObject& JsonObject::Set(const std::string& key, bool value) {
  Put(key, value ? "true" : "false", nullptr);
  return *this;
}
JsonObject& JsonObject::Set(const std::string& key, const std::string& value) {
  Put(key, JsonString(value), nullptr);
  return *this;
}
JsonObject& JsonObject::Set(const std::string& key, const JsonObject& value) {
  Put(key, "", std::make_shared<JsonObject>(value));
  return *this;
}
JsonObject& JsonObject::Set(const std::string& key, const std::vector<double>& values) {
  std::string s = "[";
  for (std::size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + JsonNumber(values[i]);
  Put(key, s + "]", nullptr);
  return *this;
}

std::string JsonObject::Dump(int indent) const {
  if (entries_.empty()) return "{}";
  const std::string pad(static_cast<std::size_t>(indent + 2), ' ');
  std::ostringstream o;
  o << "{\n";
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const Entry& e = entries_[i];
    o << pad << JsonString(e.key) << ": " << (e.object ? e.object->Dump(indent + 2) : e.scalar)
      << (i + 1 < entries_.size() ? ",\n" : "\n");
  }
  o << std::string(static_cast<std::size_t>(indent), ' ') << "}";
  return o.str();
}

}  // namespace foresight
