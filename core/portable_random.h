#pragma once
/// Draws on top of std::mt19937_64 that give the same numbers with every standard library (the
/// std:: distributions are implementation-defined), so generated data and samples are reproducible
/// bit for bit on any platform.

#include <cmath>
#include <random>

namespace foresight {

/// Uniform on [0, 1) from the top 53 bits.
inline double Uniform01(std::mt19937_64* rng) {
  return static_cast<double>((*rng)() >> 11) * 0x1.0p-53;
}

/// Uniform on [-1, 1).
inline double UniformSym(std::mt19937_64* rng) { return 2 * Uniform01(rng) - 1; }

/// Standard normal by Box-Muller (the cosine of the pair; two uniform draws per call).
inline double StandardNormal(std::mt19937_64* rng) {
  const double u1 = 1.0 - Uniform01(rng);  // (0, 1]
  const double u2 = Uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace foresight
