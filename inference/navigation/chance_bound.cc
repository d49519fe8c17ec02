#include "inference/navigation/chance_bound.h"

#include <cmath>

#include "core/error.h"

namespace foresight::nav {

double CollisionProbabilityBound(const Eigen::Vector2d& x, const Eigen::Vector2d& mean,
                                 const Eigen::Matrix2d& cov, double radius) {
  const Eigen::Vector2d d = x - mean;
  const double dist = d.norm();
  if (dist == 0.0) return 1.0;
  const Eigen::Vector2d a = d / dist;
  const double var = a.dot(cov * a);
  if (!(var > 0.0)) return dist < radius ? 1.0 : 0.0;  // deterministic pedestrian
  return 0.5 * (1.0 + std::erf((radius - dist) / std::sqrt(2.0 * var)));
}

double ErfInv(double y) {
  FS_THROW_UNLESS(y > -1.0 && y < 1.0, "ErfInv: argument ", y, " outside (-1, 1)");
  // Initial guess: Giles, "Approximating the erfinv function" (2010), single-precision branch.
  double w = -std::log((1.0 - y) * (1.0 + y));
  double p;
  if (w < 5.0) {
    w -= 2.5;
    p = 2.81022636e-08;
    for (double c : {3.43273939e-07, -3.5233877e-06, -4.39150654e-06, 0.00021858087, -0.00125372503,
                     -0.00417768164, 0.246640727, 1.50140941})
      p = c + p * w;
  } else {
    w = std::sqrt(w) - 3.0;
    p = -0.000200214257;
    for (double c : {0.000100950558, 0.00134934322, -0.00367342844, 0.00573950773, -0.0076224613,
                     0.00943887047, 1.00167406, 2.83297682})
      p = c + p * w;
  }
  double x = p * y;
  // Newton on erf(x) - y: derivative 2/sqrt(pi) exp(-x^2).
  const double two_over_sqrt_pi = 1.1283791670955126;
  for (int i = 0; i < 3; ++i) x -= (std::erf(x) - y) / (two_over_sqrt_pi * std::exp(-x * x));
  return x;
}

ChanceThreshold::ChanceThreshold(double epsilon) : epsilon_(epsilon) {
  FS_THROW_UNLESS(epsilon > 0.0 && epsilon < 1.0, "chance threshold epsilon = ", epsilon,
                  ": expected 0 < epsilon < 1");
  c_ = -ErfInv(2.0 * epsilon - 1.0);
}

bool ChanceThreshold::Exceeds(const Eigen::Vector2d& d, const Eigen::Matrix2d& cov,
                              double radius) const {
  const double dist2 = d.squaredNorm();
  if (dist2 == 0.0) return true;
  const double dist = std::sqrt(dist2);
  const double var = d.dot(cov * d) / dist2;  // a' Sigma a
  if (!(var > 0.0)) return dist < radius;
  return dist < radius + c_ * std::sqrt(2.0 * var);
}

}  // namespace foresight::nav
