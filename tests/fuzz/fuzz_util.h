#pragma once
/// What every fuzz target of tests/fuzz shares. A target defines
///   extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
/// and feeds the bytes to one loader through ExpectCleanError: the loader must either accept the
/// input or throw foresight::Error whose message names the input (its path). Any other exception,
/// an Error that does not name the file, a crash or a sanitizer report is a finding: the target
/// aborts, libFuzzer keeps the input, and the input goes to tests/fuzz/corpus/<target>/ as a
/// regression case once fixed (docs/robustness.md).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <limits>
#include <string>

#include "core/error.h"

namespace foresight::fuzz {

/// A per-process scratch file `<tmp>/foresight_fuzz_<pid>/<name>` (directory created on first use).
inline std::string ScratchPath(const std::string& name) {
  const char* tmp = std::getenv("TMPDIR");
  const std::string dir =
      std::string(tmp && *tmp ? tmp : "/tmp") + "/foresight_fuzz_" + std::to_string(::getpid());
  static const bool made = [&] { return std::system(("mkdir -p '" + dir + "'").c_str()) == 0; }();
  (void)made;
  return dir + "/" + name;
}

/// Writes the fuzz input to the scratch file `name` and returns its path.
inline std::string WriteScratch(const std::string& name, const std::uint8_t* data,
                                std::size_t size) {
  const std::string path = ScratchPath(name);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write scratch file %s\n", path.c_str());
    std::abort();
  }
  return path;
}

/// Runs `load`; accepts success or a foresight::Error whose message contains `must_name` (empty:
/// any message). Everything else aborts with the reason.
template <typename F>
void ExpectCleanError(const std::string& must_name, F&& load) {
  try {
    load();
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.empty() || (!must_name.empty() && what.find(must_name) == std::string::npos)) {
      std::fprintf(stderr, "fuzz: error does not name '%s': %s\n", must_name.c_str(), what.c_str());
      std::abort();
    }
    if (what.find('\n') != std::string::npos) {
      std::fprintf(stderr, "fuzz: error is not one line: %s\n", what.c_str());
      std::abort();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz: not a foresight::Error: %s\n", e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "fuzz: unknown exception\n");
    std::abort();
  }
}

/// Reads little pieces of the fuzz input in order (structure-aware targets); past the end it
/// returns zeros.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  std::size_t remaining() const { return pos_ < size_ ? size_ - pos_ : 0; }
  std::uint8_t Byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::uint32_t U32() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(Byte()) << (8 * i);
    return v;
  }
  std::uint64_t U64() {
    return static_cast<std::uint64_t>(U32()) | (static_cast<std::uint64_t>(U32()) << 32);
  }
  /// A double that favours the interesting values (0, -1, 1, NaN, +-inf, huge, tiny, 2^32 + 8)
  /// and otherwise reinterprets 8 bytes.
  double Double() {
    static constexpr double kSpecial[] = {0.0,           -1.0,         1.0,    0.5,
                                          1e300,         -1e300,       1e-300, 4294967304.0,
                                          -4294967304.0, 2147483648.0, 1e9,    -0.0};
    const std::uint8_t sel = Byte();
    if (sel < 96) return kSpecial[sel % (sizeof(kSpecial) / sizeof(kSpecial[0]))];
    if (sel < 112)
      return sel % 2 ? std::numeric_limits<double>::quiet_NaN()
                     : (sel % 4 == 0 ? 1 : -1) * std::numeric_limits<double>::infinity();
    const std::uint64_t bits = U64();
    double d;
    static_assert(sizeof(d) == sizeof(bits));
    __builtin_memcpy(&d, &bits, sizeof(d));
    return d;
  }
  /// The rest of the input as a string.
  std::string Rest() {
    std::string s(reinterpret_cast<const char*>(data_) + (pos_ < size_ ? pos_ : size_),
                  remaining());
    pos_ = size_;
    return s;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace foresight::fuzz
