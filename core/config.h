#pragma once
/// Typed configuration structs read from and written to YAML by one field list per struct.
///
/// A config struct lists each field once:
///
///   struct OptimConfig {
///     double lr = 1e-3;
///     template <class Archive> void Serialize(Archive* a) {
///       a->Visit("lr", &lr, Range::Positive(), "Adam learning rate");
///     }
///   };
///
/// The same Serialize() drives the strict YAML reader (unknown keys, wrong types and out-of-range
/// values are errors naming file, key path, value and expectation), the YAML writer (the resolved
/// config saved in run directories and artifacts) and the reference generator (docs/).

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/parse.h"

namespace foresight::config {

/// An allowed interval for a numeric field.
struct Range {
  std::optional<double> min, max;
  bool min_exclusive = false, max_exclusive = false;

  static Range Any() { return {}; }
  static Range Positive() { return {0.0, std::nullopt, true, false}; }
  static Range NonNegative() { return {0.0, std::nullopt, false, false}; }
  static Range AtLeast(double lo) { return {lo, std::nullopt, false, false}; }
  static Range Closed(double lo, double hi) { return {lo, hi, false, false}; }
  static Range OpenClosed(double lo, double hi) { return {lo, hi, true, false}; }
  static Range Open(double lo, double hi) { return {lo, hi, true, true}; }

  bool Contains(double v) const {
    if (std::isnan(v)) return false;
    if (min && (min_exclusive ? !(v > *min) : !(v >= *min))) return false;
    if (max && (max_exclusive ? !(v < *max) : !(v <= *max))) return false;
    return true;
  }
  std::string Describe() const;
};

/// A named set of values for an enum field: {{Kind::kA, "a"}, {Kind::kB, "b"}}.
template <typename E>
using EnumNames = std::vector<std::pair<E, const char*>>;

namespace internal {
template <typename T, typename = void>
struct IsStruct : std::false_type {};
template <typename T>
struct IsStruct<T, std::void_t<decltype(std::declval<T&>().template Serialize<int>(nullptr))>>
    : std::true_type {};

/// std::vector<S> where S is a config struct (a YAML sequence of mappings).
template <typename T>
struct IsStructVector : std::false_type {};
template <typename S>
struct IsStructVector<std::vector<S>> : IsStruct<S> {};

template <typename T>
const char* TypeName() {
  if constexpr (std::is_same_v<T, bool>)
    return "bool";
  else if constexpr (std::is_integral_v<T>)
    return "integer";
  else if constexpr (std::is_floating_point_v<T>)
    return "number";
  else
    return "string";
}
std::string JoinPath(const std::string& prefix, const std::string& key);
}  // namespace internal

// --------------------------------------------------------------------------------------------
/// Reads a YAML node into a struct, strictly.
class YamlReader {
 public:
  /// @param source file name (or "<embedded>") used in error messages.
  YamlReader(YAML::Node node, std::string source, std::string prefix = "")
      : node_(std::move(node)), source_(std::move(source)), prefix_(std::move(prefix)) {}

  template <typename T>
  void Visit(const char* key, T* value, Range range = Range::Any(), const char* doc = "") {
    const std::optional<YAML::Node> maybe = Take(key);
    if (!maybe) return;
    const YAML::Node& child = *maybe;
    const std::string path = internal::JoinPath(prefix_, key);
    if constexpr (internal::IsStruct<T>::value) {
      if (!child.IsMap()) FailAt(path, child, "a mapping");
      YamlReader sub(child, source_, path);
      value->Serialize(&sub);
      sub.CheckNoUnknownKeys();
    } else if constexpr (internal::IsStructVector<T>::value) {
      if (!child.IsSequence()) FailAt(path, child, "a list of mappings");
      T out;
      for (std::size_t i = 0; i < child.size(); ++i) {
        const std::string element = path + "[" + std::to_string(i) + "]";
        const YAML::Node item = child[i];
        if (!item.IsMap()) FailAt(element, item, "a mapping");
        typename T::value_type v{};
        YamlReader sub(item, source_, element);
        v.Serialize(&sub);
        sub.CheckNoUnknownKeys();
        out.push_back(std::move(v));
      }
      *value = std::move(out);
    } else if constexpr (IsVector<T>::value) {
      if (!child.IsSequence())
        FailAt(path, child,
               std::string("a list of ") + internal::TypeName<typename T::value_type>());
      T out;
      for (std::size_t i = 0; i < child.size(); ++i) {
        out.push_back(ReadScalar<typename T::value_type>(
            child[i], path + "[" + std::to_string(i) + "]", range));
      }
      *value = std::move(out);
    } else {
      *value = ReadScalar<T>(child, path, range);
    }
  }

  template <typename E>
  void VisitEnum(const char* key, E* value, const EnumNames<E>& names, const char* doc = "") {
    const std::optional<YAML::Node> maybe = Take(key);
    if (!maybe) return;
    const YAML::Node& child = *maybe;
    const std::string path = internal::JoinPath(prefix_, key);
    std::string expected = "one of";
    for (const auto& [e, n] : names) expected += std::string(" '") + n + "'";
    if (!child.IsScalar()) FailAt(path, child, expected);
    const std::string text = child.Scalar();
    for (const auto& [e, n] : names) {
      if (text == n) {
        *value = e;
        return;
      }
    }
    FailAt(path, child, expected);
  }

  /// After visiting every field: any key left over is an error.
  void CheckNoUnknownKeys() const;

 private:
  template <typename T>
  struct IsVector : std::false_type {};
  template <typename U>
  struct IsVector<std::vector<U>> : std::true_type {};

  /// The value of `key`, or nothing when absent or null (the default stays).
  std::optional<YAML::Node> Take(const char* key);
  [[noreturn]] void FailAt(const std::string& path, const YAML::Node& node,
                           const std::string& expected) const;

  template <typename T>
  T ReadScalar(const YAML::Node& n, const std::string& path, const Range& range) const {
    if (!n.IsScalar()) FailAt(path, n, internal::TypeName<T>());
    T v{};
    if constexpr (std::is_same_v<T, std::string>) {
      v = n.Scalar();
    } else if constexpr (std::is_same_v<T, bool>) {
      const std::string& s = n.Scalar();
      if (s == "true" || s == "True")
        v = true;
      else if (s == "false" || s == "False")
        v = false;
      else
        FailAt(path, n, "true or false");
    } else if constexpr (std::is_integral_v<T>) {
      const std::optional<long long> maybe = ParseInteger(n.Scalar());
      if (!maybe) FailAt(path, n, ExpectText<T>(range));
      const long long parsed = *maybe;
      if (parsed < static_cast<long long>(std::numeric_limits<T>::lowest()) ||
          parsed > static_cast<long long>(std::numeric_limits<T>::max()))
        FailAt(path, n, ExpectText<T>(range));
      v = static_cast<T>(parsed);
      if (!range.Contains(static_cast<double>(v))) FailAt(path, n, ExpectText<T>(range));
    } else {
      const std::optional<double> maybe = ParseDouble(n.Scalar());
      if (!maybe || !std::isfinite(*maybe)) FailAt(path, n, ExpectText<T>(range));
      const double parsed = *maybe;
      v = static_cast<T>(parsed);
      if (!range.Contains(parsed)) FailAt(path, n, ExpectText<T>(range));
    }
    return v;
  }

  template <typename T>
  static std::string ExpectText(const Range& r) {
    std::string d = r.Describe();
    return std::string("a finite ") + internal::TypeName<T>() + (d.empty() ? "" : " " + d);
  }

  YAML::Node node_;
  std::string source_, prefix_;
  std::set<std::string> seen_;
};

// --------------------------------------------------------------------------------------------
/// Writes a struct as YAML (the resolved config).
class YamlWriter {
 public:
  explicit YamlWriter(YAML::Emitter* out) : out_(out) {}

  template <typename T>
  void Visit(const char* key, T* value, Range = Range::Any(), const char* = "") {
    *out_ << YAML::Key << key << YAML::Value;
    if constexpr (internal::IsStruct<T>::value) {
      *out_ << YAML::BeginMap;
      value->Serialize(this);
      *out_ << YAML::EndMap;
    } else if constexpr (internal::IsStructVector<T>::value) {
      *out_ << YAML::BeginSeq;
      for (auto& element : *value) {
        *out_ << YAML::BeginMap;
        element.Serialize(this);
        *out_ << YAML::EndMap;
      }
      *out_ << YAML::EndSeq;
    } else if constexpr (std::is_floating_point_v<T>) {
      *out_ << FormatDouble(*value);
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      *out_ << YAML::Flow << YAML::BeginSeq;
      for (double d : *value) *out_ << FormatDouble(d);
      *out_ << YAML::EndSeq;
    } else if constexpr (std::is_same_v<T, std::vector<std::string>> ||
                         std::is_same_v<T, std::vector<int>>) {
      *out_ << YAML::Flow << YAML::BeginSeq;
      for (const auto& d : *value) *out_ << d;
      *out_ << YAML::EndSeq;
    } else {
      *out_ << *value;
    }
  }

  template <typename E>
  void VisitEnum(const char* key, E* value, const EnumNames<E>& names, const char* = "") {
    *out_ << YAML::Key << key << YAML::Value;
    for (const auto& [e, n] : names)
      if (e == *value) *out_ << n;
  }

 private:
  static std::string FormatDouble(double v);
  YAML::Emitter* out_;
};

// --------------------------------------------------------------------------------------------
/// One row of the generated config reference.
struct DocRow {
  std::string path, type, default_value, allowed, doc;
};

/// Collects key path, type, default, allowed values and description of every field.
class DocCollector {
 public:
  explicit DocCollector(std::vector<DocRow>* rows, std::string prefix = "")
      : rows_(rows), prefix_(std::move(prefix)) {}

  template <typename T>
  void Visit(const char* key, T* value, Range range = Range::Any(), const char* doc = "") {
    const std::string path = internal::JoinPath(prefix_, key);
    if constexpr (internal::IsStruct<T>::value) {
      rows_->push_back({path, "mapping", "", "", doc});
      DocCollector sub(rows_, path);
      value->Serialize(&sub);
    } else if constexpr (internal::IsStructVector<T>::value) {
      // The list itself, then the fields of one element (defaults of a default element) as
      // key[].field.
      const std::string def = value->empty() ? "[]" : std::to_string(value->size()) + " entries";
      rows_->push_back({path, "list of mapping", def, "", doc});
      typename T::value_type element{};
      DocCollector sub(rows_, path + "[]");
      element.Serialize(&sub);
    } else {
      YAML::Emitter e;
      e << YAML::Flow;
      YamlWriter w(&e);
      e << YAML::BeginMap;
      w.Visit("v", value);
      e << YAML::EndMap;
      std::string text = e.c_str();  // "{v: ...}"
      text = text.size() > 5 ? text.substr(4, text.size() - 5) : "";
      std::string type;
      if constexpr (std::is_same_v<T, std::vector<double>>)
        type = "list of number";
      else if constexpr (std::is_same_v<T, std::vector<std::string>>)
        type = "list of string";
      else if constexpr (std::is_same_v<T, std::vector<int>>)
        type = "list of integer";
      else
        type = internal::TypeName<T>();
      rows_->push_back({path, type, text, range.Describe(), doc});
    }
  }

  template <typename E>
  void VisitEnum(const char* key, E* value, const EnumNames<E>& names, const char* doc = "") {
    std::string def, allowed;
    for (const auto& [e, n] : names) {
      if (e == *value) def = n;
      allowed += (allowed.empty() ? "" : " | ") + std::string(n);
    }
    rows_->push_back({internal::JoinPath(prefix_, key), "enum", def, allowed, doc});
  }

 private:
  std::vector<DocRow>* rows_;
  std::string prefix_;
};

// --------------------------------------------------------------------------------------------
/// Applies `a.b.c=value` overrides to a YAML tree (value parsed as YAML); `list[i]` addresses an
/// existing element of a list (`groups[0].count=5`).
void ApplyOverride(YAML::Node root, const std::string& assignment);

/// Parses YAML text; errors name `source`.
YAML::Node ParseYaml(const std::string& text, const std::string& source);

/// Reads a YAML file; errors name the file.
YAML::Node LoadYamlFile(const std::string& path);

/// "key.path = a, not b" for the first leaf (in a's key order) where two trees of the same config
/// struct differ, with the values as one-line YAML; "" when they are equal. `path` prefixes keys.
std::string FirstDifference(const YAML::Node& a, const YAML::Node& b, const std::string& path);

/// Reads `node` (plus overrides) into a default-constructed T, strictly.
template <typename T>
T FromYaml(YAML::Node node, const std::string& source,
           const std::vector<std::string>& overrides = {}) {
  if (!node || node.IsNull()) node = YAML::Node(YAML::NodeType::Map);
  FS_THROW_UNLESS(node.IsMap(), source, ": the top level of a config must be a mapping");
  for (const auto& o : overrides) ApplyOverride(node, o);
  T value{};
  YamlReader reader(node, source);
  value.Serialize(&reader);
  reader.CheckNoUnknownKeys();
  return value;
}

/// Loads a config file (plus `key.path=value` overrides) into T.
template <typename T>
T LoadFile(const std::string& path, const std::vector<std::string>& overrides = {}) {
  return FromYaml<T>(LoadYamlFile(path), path, overrides);
}

/// Loads an experiment config: the strict read of `path` plus overrides, then `T::Validate(path)`,
/// the one place where a config's rules across keys live. Every experiment kind loads this way.
template <typename T>
T LoadExperimentConfig(const std::string& path, const std::vector<std::string>& overrides = {}) {
  T value = LoadFile<T>(path, overrides);
  value.Validate(path);
  return value;
}

/// The same from YAML text (an embedded default); `source` names it in errors.
template <typename T>
T ExperimentConfigFromYaml(const std::string& text, const std::string& source,
                           const std::vector<std::string>& overrides = {}) {
  T value = FromYaml<T>(ParseYaml(text, source), source, overrides);
  value.Validate(source);
  return value;
}

/// The fully resolved config as YAML text.
template <typename T>
std::string ToYaml(const T& value) {
  T copy = value;
  YAML::Emitter e;
  e << YAML::BeginMap;
  YamlWriter w(&e);
  copy.Serialize(&w);
  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

/// A Markdown table of every key of T with its default.
template <typename T>
std::string ReferenceTable() {
  T value{};
  std::vector<DocRow> rows;
  DocCollector c(&rows);
  value.Serialize(&c);
  std::ostringstream os;
  os << "| key | type | default | allowed | description |\n|---|---|---|---|---|\n";
  // A '|' inside a cell (enum choices "a | b") is escaped so the Markdown table keeps its columns.
  const auto cell = [](std::string text) {
    for (std::size_t at = text.find('|'); at != std::string::npos; at = text.find('|', at + 2))
      text.replace(at, 1, "\\|");
    return text;
  };
  for (const auto& r : rows)
    os << "| `" << r.path << "` | " << r.type << " | "
       << (r.default_value.empty() ? "" : "`" + r.default_value + "`") << " | " << cell(r.allowed)
       << " | " << cell(r.doc) << " |\n";
  return os.str();
}

}  // namespace foresight::config
