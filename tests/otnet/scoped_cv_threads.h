#pragma once
/// Sets OpenCV's thread count for a scope and restores it at exit (allocation tests: 0 runs
/// cv::parallel_for_ bodies in the caller, so no pool thread allocates its TLS mid-count).

#include <opencv2/core.hpp>

namespace foresight::otnet {

class ScopedCvThreads {
 public:
  explicit ScopedCvThreads(int threads) : saved_(cv::getNumThreads()) {
    cv::setNumThreads(threads);
  }
  ~ScopedCvThreads() { cv::setNumThreads(saved_); }
  ScopedCvThreads(const ScopedCvThreads&) = delete;
  ScopedCvThreads& operator=(const ScopedCvThreads&) = delete;

 private:
  int saved_;
};

}  // namespace foresight::otnet
