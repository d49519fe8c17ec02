#pragma once
/// Shared test utilities: error-message checks, temporary directories, finite differences,
/// a random SPAN artifact writer (torch-free) and the path of ../shared/data.

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <Eigen/Core>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/matrix_normal_head.h"

namespace foresight::testing {

/// Expects `fn` to throw foresight::Error whose message contains every `parts` entry.
inline void ExpectErrorContains(const std::function<void()>& fn,
                                const std::vector<std::string>& parts) {
  try {
    fn();
    ADD_FAILURE() << "expected foresight::Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const auto& p : parts)
      EXPECT_NE(what.find(p), std::string::npos) << "'" << p << "' not in: " << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "error message is not one line: " << what;
  }
}

/// A fresh empty directory under the system temp dir, removed at scope exit.
class TempDir {
 public:
  TempDir() {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("foresight_test_" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string File(const std::string& name) const { return (path_ / name).string(); }
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

/// While alive, files of this process cannot grow beyond `bytes` (writes fail with EFBIG, as on a
/// full disk); SIGXFSZ is ignored so the failure reaches the writer.
class ScopedFileSizeLimit {
 public:
  explicit ScopedFileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    previous_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~ScopedFileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previous_);
  }
  ScopedFileSizeLimit(const ScopedFileSizeLimit&) = delete;
  ScopedFileSizeLimit& operator=(const ScopedFileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  void (*previous_)(int) = nullptr;
};

/// d f / d x at `x` by central differences with step `h` in each coordinate.
Eigen::VectorXd CentralGradient(const std::function<double(const Eigen::VectorXd&)>& f,
                                const Eigen::VectorXd& x, double h = 1e-6);

/// |a - b| <= tol in every entry (same shapes); the failure message names the worst entry.
::testing::AssertionResult MatricesNear(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                        double tol);

/// Writes `text` to `path`.
void WriteText(const std::string& path, const std::string& text);
/// The whole text of `path` (an empty string when it cannot be read).
std::string ReadText(const std::string& path);
/// Replaces attribute `name` of `object` in an existing HDF5 file (edited-artifact tests).
void OverwriteAttr(const std::string& path, const std::string& object, const std::string& name,
                   std::int64_t value);
void OverwriteAttr(const std::string& path, const std::string& object, const std::string& name,
                   double value);
/// Keeps the first `bytes` bytes of `path`.
void Truncate(const std::string& path, std::size_t bytes);

/// ../shared/data relative to the source tree, or empty when absent (tests then skip).
std::string SharedDataDir();

/// Writes a span_predictor artifact with random weights (no LibTorch needed).
struct RandomSpanSpec {
  int observed = 8, predicted = 12, basis = 6, components = 1;
  UParam u_param = UParam::kCholesky;
  std::vector<int> hidden = {32, 32};
  double seconds_per_step = 0.4;
  bool rotate = true;
  std::uint64_t seed = 3;
  bool residual_cv = false;
};
void WriteRandomSpanArtifact(const std::string& path, const RandomSpanSpec& spec);

}  // namespace foresight::testing
