#pragma once
/// Kernel features of continuous spatiotemporal directional maps (thesis ch 4, "Generating
/// high-dimensional Features Over Space" and "From Spatial to Spatiotemporal"). Torch-free: the
/// trainer and the Eigen engine compute the very same features with this code.
///
///   spatial   phi_s(x)_j = k_s(x, xbar_j) = exp(-||x - xbar_j||^2 / (2 l_s^2)),  j < M_s,
///   temporal  phi_t(t)_k = k_t(t, tbar_k) = exp(-(t - tbar_k)^2 / (2 l_t^2)),    k < M_t,
///   spatiotemporal phi = phi_s (x) phi_t, fed to the LSTM as a sequence over the temporal inducing
///   points: step k is the vector phi_s(x) * phi_t(t)_k [M_s] (thesis: "outer product ... treated
///   as a sequence"), k = 0 .. M_t - 1.
///
/// Inducing points: spatial ones at the centres of a cells_x x cells_y grid over the extent (the
/// same positions and count as the cells of a directional grid map at that resolution); temporal
/// ones evenly spaced over [t_min, t_max] including both ends (one point: the midpoint).
/// Kernel values below exp(-cutoff^2 / 2) (distance beyond `cutoff` length scales) are exactly 0,
/// so a query only touches the inducing points within cutoff * l_s (training uses the same values).
///
/// Queries outside the extent or time range (documented and tested behaviour):
///  - t outside [t_min, t_max] is clamped to the range (the nearest known time pattern);
///  - (x, y) outside the spatial extent is NOT clamped: features decay with distance, so far from
///    every inducing point all features are 0 and the model answers its data-free mixture.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/config.h"

namespace foresight::directional {

struct FeatureConfig {
  double x_min = 0, x_max = 10, y_min = 0, y_max = 10;  ///< spatial extent (m)
  int cells_x = 10, cells_y = 10;                       ///< M_s = cells_x * cells_y inducing points
  double length_scale = 1.0;                            ///< l_s (m)
  double t_min = 0, t_max = 100;                        ///< temporal range (s)
  int time_points = 4;                                  ///< M_t temporal inducing points
  double time_length_scale = 20.0;                      ///< l_t (s)
  double cutoff = 5.0;                                  ///< kernel support in length scales
  bool auto_extent = false;      ///< replace the spatial extent by the data's bounding box
  bool auto_time_range = false;  ///< replace [t_min, t_max] by the data's time range

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("x_min", &x_min, Range::Any(), "spatial extent: x min (m)");
    a->Visit("x_max", &x_max, Range::Any(), "spatial extent: x max (m)");
    a->Visit("y_min", &y_min, Range::Any(), "spatial extent: y min (m)");
    a->Visit("y_max", &y_max, Range::Any(), "spatial extent: y max (m)");
    a->Visit("cells_x", &cells_x, Range::Closed(1, 10000),
             "spatial inducing points (and grid cells) along x");
    a->Visit("cells_y", &cells_y, Range::Closed(1, 10000),
             "spatial inducing points (and grid cells) along y");
    a->Visit("length_scale", &length_scale, Range::Positive(), "spatial RBF length scale l_s (m)");
    a->Visit("t_min", &t_min, Range::Any(), "temporal range: start (s)");
    a->Visit("t_max", &t_max, Range::Any(), "temporal range: end (s)");
    a->Visit("time_points", &time_points, Range::Closed(1, 1000),
             "temporal inducing points M_t (LSTM steps)");
    a->Visit("time_length_scale", &time_length_scale, Range::Positive(),
             "temporal RBF length scale l_t (s)");
    a->Visit("cutoff", &cutoff, Range::Closed(1, 100),
             "kernel support in length scales (beyond: exactly 0)");
    a->Visit("auto_extent", &auto_extent, Range::Any(),
             "use the data's bounding box as spatial extent (keys x_min .. y_max ignored)");
    a->Visit("auto_time_range", &auto_time_range, Range::Any(),
             "use the data's time range (keys t_min, t_max ignored)");
  }
};

/// The inducing points and kernels of a DirectionalFeatureConfig. Immutable; no allocation in
/// the query functions.
class Features {
 public:
  Features() = default;
  /// Checks the config (non-empty extent and range, positive scales) with clear Errors.
  explicit Features(const FeatureConfig& config);

  const FeatureConfig& config() const { return config_; }
  int spatial_size() const { return config_.cells_x * config_.cells_y; }  ///< M_s
  int time_size() const { return config_.time_points; }                   ///< M_t
  /// Inducing point j (row-major over x then y: j = iy * cells_x + ix).
  Eigen::Vector2d SpatialPoint(int j) const;
  double TimePoint(int k) const;
  /// t clamped to [t_min, t_max].
  double ClampTime(double t) const;

  /// The window of inducing points with a possibly non-zero feature at (x, y): ix in [ix0, ix1),
  /// iy in [iy0, iy1) (empty when the point is far outside the extent).
  struct Window {
    int ix0 = 0, ix1 = 0, iy0 = 0, iy1 = 0;
  };
  Window SpatialWindow(double x, double y) const;
  /// Spatial kernel of (x, y) against inducing point (ix, iy), 0 beyond the cutoff.
  double SpatialKernel(double x, double y, int ix, int iy) const;

  /// phi_s(x, y) [M_s] (dense, zeros outside the window). `out` must have size M_s.
  void Spatial(double x, double y, Eigen::Ref<Eigen::VectorXf> out) const;
  /// phi_t(clamp(t)) [M_t]. `out` must have size M_t.
  void Temporal(double t, Eigen::Ref<Eigen::VectorXf> out) const;
  /// Batches: row i of `out` holds the features of sample i ([n x M_s] and [n x M_t]).
  void SpatialBatch(
      const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
      Eigen::Ref<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> out) const;
  void TemporalBatch(
      const Eigen::Ref<const Eigen::VectorXd>& t,
      Eigen::Ref<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> out) const;
  /// Sparse spatial features of n samples (the non-zero entries only, the same float values as
  /// Spatial): sample i owns entries offsets[i] .. offsets[i + 1] - 1 of `index` (inducing point j)
  /// and `value`. `offsets` gets n + 1 entries. (Training uses this with an embedding bag.)
  void SpatialSparseBatch(const Eigen::Ref<const Eigen::VectorXd>& x,
                          const Eigen::Ref<const Eigen::VectorXd>& y,
                          std::vector<std::int64_t>* index, std::vector<float>* value,
                          std::vector<std::int64_t>* offsets) const;

 private:
  FeatureConfig config_;
  double dx_ = 1, dy_ = 1, inv_two_ls2_ = 0.5, inv_two_lt2_ = 0.5, cut2_s_ = 25, cut2_t_ = 25;
};

/// The config with auto_extent / auto_time_range resolved against data positions and times [n]
/// (bounding box; a degenerate range is widened). Both flags are false afterwards.
FeatureConfig ResolveExtent(const FeatureConfig& config, const Eigen::Ref<const Eigen::VectorXd>& x,
                            const Eigen::Ref<const Eigen::VectorXd>& y,
                            const Eigen::Ref<const Eigen::VectorXd>& t);

}  // namespace foresight::directional
