// Fuzz target of the strict YAML config reader with overrides (core/config.h). Input layout: when
// the input holds a 0x00 byte, the bytes before the first one are overrides, one `key.path=value`
// per line (at most 3 are used; further lines are ignored), and the bytes after it are the YAML
// text; without a 0x00 byte the whole input is YAML and there are no overrides. The text is read
// as four experiment configs (SPAN predictor, occupancy, directional, navigation), each once from
// text (ExperimentConfigFromYaml, source "fuzz-config") and once from a file
// (LoadExperimentConfig); every error must name the source or the file, except that an error about
// a malformed override names that override (`override '<text>'`), which is the input at fault
// (ApplyOverride in core/config.h takes no source).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/config.h"
#include "tests/fuzz/fuzz_util.h"
#include "training/directional/config.h"
#include "training/navigation/config.h"
#include "training/occupancy/config.h"
#include "training/span/config.h"

namespace {

/// Runs `load`, turning an Error that names the failing override into success (it is checked to
/// be one line by rethrowing it with the override as the name to look for).
template <typename F>
void ExpectCleanErrorOrOverride(const std::string& must_name,
                                const std::vector<std::string>& overrides, F&& load) {
  std::string named = must_name;
  try {
    load();
    return;
  } catch (const foresight::Error& e) {
    const std::string what = e.what();
    for (const std::string& o : overrides)
      if (what.find(must_name) == std::string::npos &&
          what.find("override '" + o + "'") != std::string::npos)
        named = "override '" + o + "'";
  } catch (...) {
  }
  foresight::fuzz::ExpectCleanError(named, load);
}

template <typename T>
void LoadBoth(const std::string& text, const std::string& path,
              const std::vector<std::string>& overrides) {
  static const std::string kSource = "fuzz-config";
  ExpectCleanErrorOrOverride(kSource, overrides, [&] {
    (void)foresight::config::ExperimentConfigFromYaml<T>(text, kSource, overrides);
  });
  ExpectCleanErrorOrOverride(
      path, overrides, [&] { (void)foresight::config::LoadExperimentConfig<T>(path, overrides); });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* begin = reinterpret_cast<const char*>(data);
  const void* zero = size ? std::memchr(data, 0, size) : nullptr;
  std::vector<std::string> overrides;
  std::string text(begin, size);
  if (zero) {
    const std::size_t at = static_cast<std::size_t>(static_cast<const char*>(zero) - begin);
    const std::string head(begin, at);
    text.assign(begin + at + 1, size - at - 1);
    std::size_t from = 0;
    while (overrides.size() < 3 && from <= head.size()) {
      std::size_t eol = head.find('\n', from);
      if (eol == std::string::npos) eol = head.size();
      if (eol > from) overrides.push_back(head.substr(from, eol - from));
      from = eol + 1;
    }
  }
  const std::string path = foresight::fuzz::WriteScratch(
      "config.yaml", reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  LoadBoth<foresight::span::ExperimentConfig>(text, path, overrides);
  LoadBoth<foresight::occupancy::ExperimentConfig>(text, path, overrides);
  LoadBoth<foresight::directional::ExperimentConfig>(text, path, overrides);
  LoadBoth<foresight::nav::ExperimentConfig>(text, path, overrides);
  return 0;
}
