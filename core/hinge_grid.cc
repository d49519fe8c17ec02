#include "core/hinge_grid.h"

#include "core/error.h"

namespace foresight {

HingeGrid::HingeGrid(const HingeGridConfig& config) : config_(config) {
  const auto& c = config;
  FS_THROW_UNLESS(std::isfinite(c.x_min) && std::isfinite(c.x_max) && c.x_max > c.x_min,
                  "hinge grid: x range [", c.x_min, ", ", c.x_max, ") is empty or not finite");
  FS_THROW_UNLESS(std::isfinite(c.y_min) && std::isfinite(c.y_max) && c.y_max > c.y_min,
                  "hinge grid: y range [", c.y_min, ", ", c.y_max, ") is empty or not finite");
  FS_THROW_UNLESS(c.spacing > 0 && c.gamma > 0 && c.cutoff_radius > 0, "hinge grid: spacing ",
                  c.spacing, ", gamma ", c.gamma, " and cutoff_radius ", c.cutoff_radius,
                  " must be positive");
  const double fx = (c.x_max - c.x_min) / c.spacing, fy = (c.y_max - c.y_min) / c.spacing;
  FS_THROW_UNLESS(fx * fy <= 67108864.0, "hinge grid: ", fx, " x ", fy,
                  " inducing points is too many (max 2^26)");
  nx_ = std::max(1, static_cast<int>(std::lround(fx)));
  ny_ = std::max(1, static_cast<int>(std::lround(fy)));
  // Checked before the cast: a huge cut-off would overflow the int.
  const double half_window = std::floor(c.cutoff_radius / c.spacing);
  FS_THROW_UNLESS(half_window <= 31, "hinge grid: cutoff_radius ", c.cutoff_radius,
                  " spans more than 31 ", "inducing points of spacing ", c.spacing, " per side");
  window_ = 2 * static_cast<int>(half_window) + 2;
  cutoff2_ = c.cutoff_radius * c.cutoff_radius;
}

bool HingeGrid::SameFeatures(const HingeGrid& o) const {
  const auto& a = config_;
  const auto& b = o.config_;
  return nx_ == o.nx_ && ny_ == o.ny_ && a.x_min == b.x_min && a.y_min == b.y_min &&
         a.spacing == b.spacing && a.gamma == b.gamma && a.cutoff_radius == b.cutoff_radius;
}

std::string HingeGrid::Describe() const {
  return internal::Concat(nx_, " x ", ny_, " inducing points from (", config_.x_min, ", ",
                          config_.y_min, ") every ", config_.spacing, " m, gamma ", config_.gamma,
                          ", cut-off ", config_.cutoff_radius, " m");
}

}  // namespace foresight
