#pragma once
/// Sparse squared-exponential ("hinged") features on a regular grid of inducing points, the feature
/// map of Hilbert maps and (Fast-)BHMs (thesis ch 2 "Hilbert Maps", ch 3):
///   phi_t(x) = exp(-gamma ||x - c_t||^2),   c_t on a grid, t = iy * nx + ix,
/// truncated to zero beyond `cutoff_radius` so a point touches only the inducing points near it and
/// every cost is linear in the number of points (Fast-BHM). The separable form
///   exp(-gamma (dx^2 + dy^2)) = exp(-gamma dx^2) exp(-gamma dy^2)
/// needs one exponential per nearby row and column instead of one per feature.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/config.h"

namespace foresight {

struct HingeGridConfig {
  double x_min = -20,
         x_max = 20;  ///< m; inducing x = x_min + i * spacing, i < round((x_max - x_min) / spacing)
  double y_min = -25, y_max = 10;  ///< m; likewise in y
  double spacing = 0.5;            ///< m between neighbouring inducing points
  double gamma = 6.71;             ///< 1/m^2, kernel exp(-gamma d^2)
  double cutoff_radius = 1.0;      ///< m; features farther than this are zero (exp(-6.71) = 0.0012)

  template <class A>
  void Serialize(A* a) {
    a->Visit("x_min", &x_min, config::Range::Any(), "first inducing x (m)");
    a->Visit("x_max", &x_max, config::Range::Any(), "end of the inducing x range, exclusive (m)");
    a->Visit("y_min", &y_min, config::Range::Any(), "first inducing y (m)");
    a->Visit("y_max", &y_max, config::Range::Any(), "end of the inducing y range, exclusive (m)");
    a->Visit("spacing", &spacing, config::Range::Positive(),
             "distance between inducing points (m)");
    a->Visit("gamma", &gamma, config::Range::Positive(), "RBF kernel exp(-gamma d^2) (1/m^2)");
    a->Visit("cutoff_radius", &cutoff_radius, config::Range::Positive(),
             "features of inducing points farther than this are zero (m)");
  }
};

class HingeGrid {
 public:
  HingeGrid() = default;
  /// Checks the extent (x_max > x_min, y_max > y_min, at least one point per axis, at most
  /// 2^26 features) and throws an Error naming the offending values otherwise.
  explicit HingeGrid(const HingeGridConfig& config);

  const HingeGridConfig& config() const { return config_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int size() const { return nx_ * ny_; }
  double gamma() const { return config_.gamma; }
  /// Upper bound on the number of non-zero features of one point.
  int max_active() const { return window_ * window_; }
  Eigen::Vector2d Centre(int t) const {
    return {config_.x_min + (t % nx_) * config_.spacing,
            config_.y_min + (t / nx_) * config_.spacing};
  }
  /// True when two grids give identical features (same inducing points, gamma and cut-off).
  bool SameFeatures(const HingeGrid& other) const;
  std::string Describe() const;

  /// Non-zero features of the point (x, y): writes indices and values to idx[0..k), phi[0..k) and
  /// returns k <= max_active(). No allocation.
  int Features(double x, double y, int* idx, double* phi) const {
    return Visit<false>(x, y, idx, phi, nullptr, nullptr);
  }
  /// As Features(), plus the partial derivatives dphi/dx, dphi/dy (1/m).
  int FeaturesWithGradient(double x, double y, int* idx, double* phi, double* dphi_dx,
                           double* dphi_dy) const {
    return Visit<true>(x, y, idx, phi, dphi_dx, dphi_dy);
  }

 private:
  template <bool kGradient>
  int Visit(double x, double y, int* idx, double* phi, double* gx, double* gy) const;

  HingeGridConfig config_;
  int nx_ = 0, ny_ = 0;
  int window_ = 0;      ///< inducing points per axis within the cut-off
  double cutoff2_ = 0;  ///< cutoff_radius^2
};

template <bool kGradient>
int HingeGrid::Visit(double x, double y, int* idx, double* phi, double* gx, double* gy) const {
  // Not finite: no features (the caller sees the prior). Also keeps the casts below defined.
  if (!(std::abs(x) < 1e12 && std::abs(y) < 1e12)) return 0;
  const double s = config_.spacing, r = config_.cutoff_radius;
  const double fx = (x - config_.x_min) / s, fy = (y - config_.y_min) / s;
  const double lo_x = std::ceil(fx - r / s), hi_x = std::floor(fx + r / s);
  const double lo_y = std::ceil(fy - r / s), hi_y = std::floor(fy + r / s);
  // Off the grid: return before casting, since far points (|x| / s > 2^31) overflow an int.
  if (!(hi_x >= 0 && lo_x <= nx_ - 1 && hi_y >= 0 && lo_y <= ny_ - 1)) return 0;
  const int ix0 = std::max(0, static_cast<int>(lo_x)),
            ix1 = std::min(nx_ - 1, static_cast<int>(hi_x));
  const int iy0 = std::max(0, static_cast<int>(lo_y)),
            iy1 = std::min(ny_ - 1, static_cast<int>(hi_y));
  // Row and column factors (window_ is small: at most 2 r / s + 1 entries each).
  constexpr int kMaxWindow = 64;
  double ex[kMaxWindow], dx[kMaxWindow], ey[kMaxWindow], dy[kMaxWindow];
  const int cx = ix1 - ix0 + 1, cy = iy1 - iy0 + 1;
  for (int i = 0; i < cx; ++i) {
    dx[i] = x - (config_.x_min + (ix0 + i) * s);
    ex[i] = std::exp(-config_.gamma * dx[i] * dx[i]);
  }
  for (int j = 0; j < cy; ++j) {
    dy[j] = y - (config_.y_min + (iy0 + j) * s);
    ey[j] = std::exp(-config_.gamma * dy[j] * dy[j]);
  }
  int k = 0;
  const double m2g = -2.0 * config_.gamma;
  for (int j = 0; j < cy; ++j) {
    const double dy2 = dy[j] * dy[j];
    const int row = (iy0 + j) * nx_ + ix0;
    for (int i = 0; i < cx; ++i) {
      if (dx[i] * dx[i] + dy2 > cutoff2_) continue;
      const double v = ex[i] * ey[j];
      idx[k] = row + i;
      phi[k] = v;
      if constexpr (kGradient) {
        gx[k] = m2g * dx[i] * v;
        gy[k] = m2g * dy[j] * v;
      }
      ++k;
    }
  }
  return k;
}

}  // namespace foresight
