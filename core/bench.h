#pragma once
/// What every benchmark shares: one steady clock, elapsed time, and the median of repeated runs.
/// Benchmarks print figures (`foresight bench`); tests never time anything.

#include <algorithm>
#include <chrono>
#include <vector>

#include "core/error.h"

namespace foresight::bench {

using Clock = std::chrono::steady_clock;

/// Microseconds from t0 to t1.
inline double Micros(Clock::time_point t0, Clock::time_point t1) {
  return std::chrono::duration<double, std::micro>(t1 - t0).count();
}

/// Seconds from t0 to now.
inline double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// The median (the upper one of an even count) of a non-empty sample.
inline double Median(std::vector<double> v) {
  FS_THROW_UNLESS(!v.empty(), "bench: median of no measurements");
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// The median over `repeats` runs of f, in seconds.
template <class F>
double MedianSeconds(int repeats, F&& f) {
  std::vector<double> t;
  t.reserve(static_cast<std::size_t>(repeats));
  for (int r = 0; r < repeats; ++r) {
    const auto s = Clock::now();
    f();
    t.push_back(SecondsSince(s));
  }
  return Median(std::move(t));
}

/// The median over `repeats` runs of the mean time of one call of f(i), i = 0..calls-1, in
/// seconds.
template <class F>
double SecondsPerCall(int repeats, int calls, F&& f) {
  std::vector<double> t;
  t.reserve(static_cast<std::size_t>(repeats));
  for (int r = 0; r < repeats; ++r) {
    const auto s = Clock::now();
    for (int i = 0; i < calls; ++i) f(i);
    t.push_back(SecondsSince(s) / calls);
  }
  return Median(std::move(t));
}

}  // namespace foresight::bench
