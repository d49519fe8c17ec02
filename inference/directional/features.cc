#include "inference/directional/features.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace foresight::directional {

Features::Features(const FeatureConfig& c) : config_(c) {
  FS_THROW_UNLESS(std::isfinite(c.x_min) && std::isfinite(c.x_max) && c.x_max > c.x_min &&
                      std::isfinite(c.y_min) && std::isfinite(c.y_max) && c.y_max > c.y_min,
                  "directional features: empty spatial extent x [", c.x_min, ", ", c.x_max,
                  "], y [", c.y_min, ", ", c.y_max, "]");
  FS_THROW_UNLESS(std::isfinite(c.t_min) && std::isfinite(c.t_max) && c.t_max >= c.t_min,
                  "directional features: bad time range [", c.t_min, ", ", c.t_max, "]");
  FS_THROW_UNLESS(c.cells_x >= 1 && c.cells_y >= 1 && c.time_points >= 1,
                  "directional features: ", c.cells_x, " x ", c.cells_y, " x ", c.time_points,
                  " inducing points");
  FS_THROW_UNLESS(c.length_scale > 0 && c.time_length_scale > 0 && c.cutoff > 0,
                  "directional features: length scales and cutoff must be positive (got ",
                  c.length_scale, ", ", c.time_length_scale, ", ", c.cutoff, ")");
  dx_ = (c.x_max - c.x_min) / c.cells_x;
  dy_ = (c.y_max - c.y_min) / c.cells_y;
  inv_two_ls2_ = 1.0 / (2.0 * c.length_scale * c.length_scale);
  inv_two_lt2_ = 1.0 / (2.0 * c.time_length_scale * c.time_length_scale);
  cut2_s_ = c.cutoff * c.cutoff * c.length_scale * c.length_scale;
  cut2_t_ = c.cutoff * c.cutoff * c.time_length_scale * c.time_length_scale;
}

Eigen::Vector2d Features::SpatialPoint(int j) const {
  const int ix = j % config_.cells_x, iy = j / config_.cells_x;
  return {config_.x_min + (ix + 0.5) * dx_, config_.y_min + (iy + 0.5) * dy_};
}

double Features::TimePoint(int k) const {
  if (config_.time_points == 1) return 0.5 * (config_.t_min + config_.t_max);
  return config_.t_min + (config_.t_max - config_.t_min) * k / (config_.time_points - 1);
}

double Features::ClampTime(double t) const { return std::clamp(t, config_.t_min, config_.t_max); }

Features::Window Features::SpatialWindow(double x, double y) const {
  const double r = config_.cutoff * config_.length_scale;
  // Centre of cell i is x_min + (i + 0.5) dx; cells with |centre - x| <= r.
  auto range = [r](double v, double lo, double d, int n, int* i0, int* i1) {
    const double a = std::ceil((v - r - lo) / d - 0.5);
    const double b = std::floor((v + r - lo) / d - 0.5) + 1.0;
    *i0 = static_cast<int>(std::clamp(a, 0.0, static_cast<double>(n)));
    *i1 = static_cast<int>(std::clamp(b, 0.0, static_cast<double>(n)));
    if (*i1 < *i0) *i1 = *i0;
  };
  Window w;
  if (!std::isfinite(x) || !std::isfinite(y)) return w;  // callers reject NaN queries
  range(x, config_.x_min, dx_, config_.cells_x, &w.ix0, &w.ix1);
  range(y, config_.y_min, dy_, config_.cells_y, &w.iy0, &w.iy1);
  return w;
}

double Features::SpatialKernel(double x, double y, int ix, int iy) const {
  const double ex = x - (config_.x_min + (ix + 0.5) * dx_);
  const double ey = y - (config_.y_min + (iy + 0.5) * dy_);
  const double d2 = ex * ex + ey * ey;
  return d2 > cut2_s_ ? 0.0 : std::exp(-d2 * inv_two_ls2_);
}

void Features::Spatial(double x, double y, Eigen::Ref<Eigen::VectorXf> out) const {
  FS_THROW_UNLESS(out.size() == spatial_size(), "directional features: output has ", out.size(),
                  " entries, expected ", spatial_size());
  out.setZero();
  const Window w = SpatialWindow(x, y);
  for (int iy = w.iy0; iy < w.iy1; ++iy)
    for (int ix = w.ix0; ix < w.ix1; ++ix)
      out[iy * config_.cells_x + ix] = static_cast<float>(SpatialKernel(x, y, ix, iy));
}

void Features::Temporal(double t, Eigen::Ref<Eigen::VectorXf> out) const {
  FS_THROW_UNLESS(out.size() == time_size(), "directional features: output has ", out.size(),
                  " entries, expected ", time_size());
  const double tc = ClampTime(t);
  for (int k = 0; k < time_size(); ++k) {
    const double d = tc - TimePoint(k);
    out[k] = d * d > cut2_t_ ? 0.0f : static_cast<float>(std::exp(-d * d * inv_two_lt2_));
  }
}

void Features::SpatialBatch(
    const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
    Eigen::Ref<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> out) const {
  FS_THROW_UNLESS(x.size() == y.size() && out.rows() == x.size() && out.cols() == spatial_size(),
                  "directional features: batch shapes x ", x.size(), ", y ", y.size(), ", out ",
                  out.rows(), " x ", out.cols());
  for (Eigen::Index i = 0; i < x.size(); ++i) Spatial(x[i], y[i], out.row(i).transpose());
}

void Features::TemporalBatch(
    const Eigen::Ref<const Eigen::VectorXd>& t,
    Eigen::Ref<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> out) const {
  FS_THROW_UNLESS(out.rows() == t.size() && out.cols() == time_size(),
                  "directional features: batch shapes t ", t.size(), ", out ", out.rows(), " x ",
                  out.cols());
  for (Eigen::Index i = 0; i < t.size(); ++i) Temporal(t[i], out.row(i).transpose());
}

void Features::SpatialSparseBatch(const Eigen::Ref<const Eigen::VectorXd>& x,
                                  const Eigen::Ref<const Eigen::VectorXd>& y,
                                  std::vector<std::int64_t>* index, std::vector<float>* value,
                                  std::vector<std::int64_t>* offsets) const {
  FS_THROW_UNLESS(x.size() == y.size(), "directional features: batch shapes x ", x.size(), ", y ",
                  y.size());
  index->clear();
  value->clear();
  offsets->assign(1, 0);
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const Window w = SpatialWindow(x[i], y[i]);
    for (int iy = w.iy0; iy < w.iy1; ++iy)
      for (int ix = w.ix0; ix < w.ix1; ++ix) {
        const float phi = static_cast<float>(SpatialKernel(x[i], y[i], ix, iy));
        if (phi == 0.0f) continue;
        index->push_back(static_cast<std::int64_t>(iy) * config_.cells_x + ix);
        value->push_back(phi);
      }
    offsets->push_back(static_cast<std::int64_t>(index->size()));
  }
}

FeatureConfig ResolveExtent(const FeatureConfig& config, const Eigen::Ref<const Eigen::VectorXd>& x,
                            const Eigen::Ref<const Eigen::VectorXd>& y,
                            const Eigen::Ref<const Eigen::VectorXd>& t) {
  FeatureConfig c = config;
  if (!c.auto_extent && !c.auto_time_range) return c;
  FS_THROW_UNLESS(x.size() > 0 && x.size() == y.size() && x.size() == t.size() && x.allFinite() &&
                      y.allFinite() && t.allFinite(),
                  "directional features: auto_extent / auto_time_range need finite data (got ",
                  x.size(), " samples)");
  if (c.auto_extent) {
    c.x_min = x.minCoeff();
    c.x_max = x.maxCoeff();
    c.y_min = y.minCoeff();
    c.y_max = y.maxCoeff();
    if (c.x_max - c.x_min < 1e-6) c.x_min -= 0.5, c.x_max += 0.5;
    if (c.y_max - c.y_min < 1e-6) c.y_min -= 0.5, c.y_max += 0.5;
  }
  if (c.auto_time_range) {
    c.t_min = t.minCoeff();
    c.t_max = t.maxCoeff();
    if (c.t_max - c.t_min < 1e-6) c.t_max = c.t_min + 1.0;
  }
  c.auto_extent = c.auto_time_range = false;
  return c;
}

}  // namespace foresight::directional
