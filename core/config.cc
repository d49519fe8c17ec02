#include "core/config.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>

#include "core/one_line.h"

namespace foresight::config {

std::string Range::Describe() const {
  auto fmt = [](double v) {
    std::ostringstream os;
    os << std::setprecision(10) << v;
    return os.str();
  };
  if (min && max)
    return std::string("in ") + (min_exclusive ? "(" : "[") + fmt(*min) + ", " + fmt(*max) +
           (max_exclusive ? ")" : "]");
  if (min) return std::string(min_exclusive ? "> " : ">= ") + fmt(*min);
  if (max) return std::string(max_exclusive ? "< " : "<= ") + fmt(*max);
  return "";
}

namespace internal {
std::string JoinPath(const std::string& prefix, const std::string& key) {
  return prefix.empty() ? key : prefix + "." + key;
}
}  // namespace internal

std::optional<YAML::Node> YamlReader::Take(const char* key) {
  seen_.insert(key);
  if (!node_.IsMap()) return std::nullopt;
  const YAML::Node& const_node = node_;  // const lookup: never inserts the key
  YAML::Node child = const_node[key];
  if (!child.IsDefined() || child.IsNull()) return std::nullopt;
  return child;
}

void YamlReader::FailAt(const std::string& path, const YAML::Node& node,
                        const std::string& expected) const {
  std::string text;
  if (node.IsScalar())
    text = "'" + node.Scalar() + "'";
  else if (node.IsSequence())
    text = "a list";
  else if (node.IsMap())
    text = "a mapping";
  else
    text = "nothing";
  std::string where = source_;
  if (node.Mark().line >= 0 && source_.rfind('<', 0) != 0)
    where += ":" + std::to_string(node.Mark().line + 1);
  Fail(where, ": key '", path, "': value ", text, " is not ", expected);
}

void YamlReader::CheckNoUnknownKeys() const {
  if (!node_.IsMap()) return;
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (!seen_.count(key)) {
      std::string known;
      for (const auto& s : seen_) known += (known.empty() ? "" : ", ") + s;
      std::string where = source_;
      if (kv.first.Mark().line >= 0 && source_.rfind('<', 0) != 0)
        where += ":" + std::to_string(kv.first.Mark().line + 1);
      Fail(where, ": unknown key '", internal::JoinPath(prefix_, key),
           "' (known keys here: ", known, ")");
    }
  }
}

std::string YamlWriter::FormatDouble(double v) {
  std::ostringstream os;
  os << std::setprecision(17) << v;
  std::string s = os.str();
  // Shortest representation that round-trips.
  for (int p = 1; p <= 17; ++p) {
    std::ostringstream t;
    t << std::setprecision(p) << v;
    if (std::strtod(t.str().c_str(), nullptr) == v) {  // strtod: no throw on subnormals
      s = t.str();
      break;
    }
  }
  if (s.find_first_of(".eE") == std::string::npos && s.find("inf") == std::string::npos &&
      s.find("nan") == std::string::npos)
    s += ".0";
  return s;
}

namespace {
// yaml-cpp's Node::operator= assigns through the handle, so walk by recursion (copy-construct
// only).
void SetPath(YAML::Node node, const std::vector<std::string>& keys, std::size_t i,
             const YAML::Node& value, const std::string& assignment) {
  // `name[k]`: element k of an existing list of mappings (e.g. groups[0].count=5).
  const auto bracket = keys[i].find('[');
  if (bracket != std::string::npos) {
    const std::string name = keys[i].substr(0, bracket);
    const std::string index_text = keys[i].substr(bracket + 1, keys[i].size() - bracket - 2);
    const std::optional<long long> index = ParseInteger(index_text);
    FS_THROW_UNLESS(!name.empty() && keys[i].back() == ']' && index && *index >= 0, "override '",
                    assignment, "': '", keys[i], "' is not of the form key[index]");
    YAML::Node list = node[name];
    FS_THROW_UNLESS(list.IsSequence(), "override '", assignment, "': '", name,
                    "' is not a list in the config");
    FS_THROW_UNLESS(static_cast<std::size_t>(*index) < list.size(), "override '", assignment,
                    "': '", name, "' has ", list.size(), " elements, no index ", *index);
    if (i + 1 == keys.size()) {
      list[static_cast<std::size_t>(*index)] = value;
      return;
    }
    YAML::Node element = list[static_cast<std::size_t>(*index)];
    FS_THROW_UNLESS(element.IsMap(), "override '", assignment, "': '", keys[i],
                    "' is not a mapping in the config");
    SetPath(element, keys, i + 1, value, assignment);
    return;
  }
  if (i + 1 == keys.size()) {
    node[keys[i]] = value;
    return;
  }
  if (!node[keys[i]].IsDefined() || node[keys[i]].IsNull())
    node[keys[i]] = YAML::Node(YAML::NodeType::Map);
  YAML::Node child = node[keys[i]];
  FS_THROW_UNLESS(child.IsMap(), "override '", assignment, "': '", keys[i],
                  "' is not a mapping in the config");
  SetPath(child, keys, i + 1, value, assignment);
}
}  // namespace

void ApplyOverride(YAML::Node root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  FS_THROW_UNLESS(eq != std::string::npos && eq > 0, "override '", assignment,
                  "' is not of the form key.path=value");
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  YAML::Node value = ParseYaml(text.empty() ? "''" : text, "override '" + assignment + "'");
  std::vector<std::string> keys;
  std::stringstream ss(path);
  for (std::string k; std::getline(ss, k, '.');) {
    FS_THROW_UNLESS(!k.empty(), "override '", assignment, "': empty key in path '", path, "'");
    keys.push_back(k);
  }
  SetPath(root, keys, 0, value, assignment);
}

namespace {
/// A config scalar (key or value) is one line of text: a line break or another control character
/// (tab aside) is refused here, so that no later message quoting the value spans lines.
void RefuseControlCharacters(const YAML::Node& scalar, const std::string& source) {
  const std::string& text = scalar.Scalar();
  const bool bad = std::any_of(text.begin(), text.end(), [](char ch) {
    const auto u = static_cast<unsigned char>(ch);
    return (u < 0x20 && ch != '\t') || u == 0x7f;
  });
  FS_THROW_UNLESS(!bad, source, ":", scalar.Mark().line + 1, ": '", OneLine(text),
                  "' holds a line break or control character; config keys and values are one line");
}

/// yaml-cpp keeps both entries of a duplicated key and answers lookups with the first, so a
/// repeated key would be silently ignored: refuse it, naming both lines. Keys must be scalars
/// (names), and every scalar one line (RefuseControlCharacters).
void RefuseDuplicateKeys(const YAML::Node& node, const std::string& source) {
  if (node.IsScalar()) RefuseControlCharacters(node, source);
  if (node.IsSequence()) {
    for (const auto& item : node) RefuseDuplicateKeys(item, source);
    return;
  }
  if (!node.IsMap()) return;
  std::map<std::string, int> seen;  // key -> 1-based line
  for (const auto& item : node) {
    const int line = item.first.Mark().line + 1;
    FS_THROW_UNLESS(item.first.IsScalar() || item.first.IsNull(), source, ":", line, ": a key is ",
                    item.first.IsSequence() ? "a list" : "a mapping", "; config keys are names");
    if (item.first.IsScalar()) {
      RefuseControlCharacters(item.first, source);
      const std::string key = item.first.Scalar();
      const auto [it, inserted] = seen.emplace(key, line);
      FS_THROW_UNLESS(inserted, source, ":", line, ": key '", key, "' is repeated (first at line ",
                      it->second, "); give each key once");
    }
    RefuseDuplicateKeys(item.second, source);
  }
}
}  // namespace

YAML::Node ParseYaml(const std::string& text, const std::string& source) {
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    Fail(source, ":", e.mark.line + 1, ": invalid YAML: ", OneLine(e.msg));
  }
  RefuseDuplicateKeys(node, source);
  return node;
}

namespace {
std::string Flow(const YAML::Node& node) {
  YAML::Emitter e;
  e.SetSeqFormat(YAML::Flow);
  e.SetMapFormat(YAML::Flow);
  e << node;
  return e.c_str();
}
}  // namespace

std::string FirstDifference(const YAML::Node& a, const YAML::Node& b, const std::string& path) {
  if (a.IsMap() && b.IsMap()) {
    for (const auto& kv : a) {
      const std::string key = kv.first.as<std::string>();
      const std::string d = FirstDifference(kv.second, b[key], internal::JoinPath(path, key));
      if (!d.empty()) return d;
    }
    return "";
  }
  return Flow(a) == Flow(b) ? "" : path + " = " + Flow(a) + ", not " + Flow(b);
}

YAML::Node LoadYamlFile(const std::string& path) {
  // Configs are a few kilobytes; a huge file is a mistake (and would take gigabytes to parse).
  constexpr std::uintmax_t kMaxConfigBytes = 1 << 20;
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  FS_THROW_UNLESS(!ec || !std::filesystem::exists(path), path, ": cannot read config file (",
                  ec.message(), ")");
  FS_THROW_UNLESS(ec || bytes <= kMaxConfigBytes, path, ": config file has ", bytes,
                  " bytes; at most ", kMaxConfigBytes, " are accepted");
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open config file");
  std::stringstream ss;
  ss << in.rdbuf();
  const YAML::Node node = ParseYaml(ss.str(), path);
  FS_THROW_UNLESS(node && !node.IsNull(), path,
                  ": config file is empty (nothing but comments or blank lines)");
  return node;
}

}  // namespace foresight::config
