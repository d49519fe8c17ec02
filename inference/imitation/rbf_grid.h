#pragma once
/// Gaussian radial basis functions on a regular grid of inducing states in D = 2 or 3 dimensions,
/// truncated beyond a cut-off radius so that a query touches only the inducing states near it
/// (thesis ch 8, eq. vecfieldeqn; errata: the Gaussian k(s, s_hat) = exp(-gamma ||s - s_hat||^2)).
///   phi_t(s) = exp(-gamma ||s - c_t||^2) if ||s - c_t|| <= cutoff_radius, else 0,
///   c_t = lower + spacing * (i_0, ..., i_{D-1}),  t = i_0 + counts_0 (i_1 + counts_1 i_2).
/// The separable form exp(-gamma sum_a d_a^2) = prod_a exp(-gamma d_a^2) needs two exponentials
/// per axis and query (Windows).
///
/// The truncation makes phi_t jump by truncation() = exp(-gamma cutoff_radius^2) across the cut-off
/// sphere, so fields built on it are discontinuous by up to that times their weights: flows are
/// then invertible only to about that level (rbf_flow.h). Choose gamma cutoff_radius^2 >= ~18
/// (truncation <= 1.5e-8) where exact inverses matter. Shared by the imitation flow (rbf_flow.h)
/// and the obstacle occupancy field (occupancy_field.h); the LibTorch trainer (models/imitation)
/// uses the same definition.

#include <Eigen/Core>
#include <array>
#include <string>

namespace foresight::imitation {

template <int D>
using Vec = Eigen::Matrix<double, D, 1>;
template <int D>
using Mat = Eigen::Matrix<double, D, D>;

/// The grid. Valid when counts >= 1 on every axis, spacing > 0, gamma > 0, cutoff_radius > 0,
/// at most 2^22 inducing states and at most RbfFeatures<D>::kCapacity states inside the cut-off
/// window (2 floor(cutoff / spacing) + 1 per axis).
template <int D>
struct RbfGridSpec {
  Vec<D> lower = Vec<D>::Zero();  ///< first inducing state
  std::array<int, D> counts{};    ///< inducing states per axis
  double spacing = 0.1;           ///< distance between neighbouring states
  double gamma = 50;              ///< kernel exp(-gamma d^2)
  double cutoff_radius = 0.3;     ///< features of states farther than this are zero
};

/// The non-zero features at one point, filled by RbfGrid::Evaluate. Fixed capacity (allocate one
/// per workspace, on the heap for D = 3): no allocation per query.
template <int D>
struct RbfFeatures {
  static constexpr int kCapacity = D == 2 ? 1024 : 4096;  // 32^2, 16^3
  int count = 0;                                          ///< non-zero features
  std::array<int, kCapacity> index;                       ///< inducing-state index t
  std::array<double, kCapacity> phi;                      ///< phi_t(s)
  std::array<Vec<D>, kCapacity> offset;  ///< s - c_t (gradient = -2 gamma phi offset)
};

template <int D>
class RbfGrid {
 public:
  RbfGrid() = default;
  /// Checks the spec; an Error naming the offending value otherwise (`source` prefixes it).
  explicit RbfGrid(const RbfGridSpec<D>& spec, const std::string& source = "rbf grid");
  /// The smallest grid covering [lo, hi] (per axis) padded by `margin` with `spacing`.
  static RbfGridSpec<D> Covering(const Vec<D>& lo, const Vec<D>& hi, double margin, double spacing,
                                 double gamma, double cutoff_radius);

  const RbfGridSpec<D>& spec() const { return spec_; }
  int size() const { return size_; }
  double gamma() const { return spec_.gamma; }
  /// exp(-gamma cutoff_radius^2): the largest jump of one feature at the cut-off.
  double truncation() const { return truncation_; }
  Vec<D> Centre(int t) const;

  /// Non-zero features at s into `out` (no allocation). Non-finite s gives no features.
  void Evaluate(const Vec<D>& s, RbfFeatures<D>* out) const;

  /// Most inducing states per axis inside the cut-off window (checked by the constructor).
  static constexpr int kMaxWindow = 64;
  /// The separable factors of the features at s, per axis a: the window of states within the
  /// cut-off radius on that axis, first[a] .. first[a] + n[a] - 1, their offsets d = s_a - c_a and
  /// factors e = exp(-gamma d^2) (two exponentials per axis: from the state nearest s outward by
  /// the recurrence e_{k+1} = e_k exp(-gamma h^2) exp(-2 gamma h |d_k|), whose second factor itself
  /// shrinks by exp(-2 gamma h^2) per state; every factor the recurrence multiplies by is at most
  /// 1, so nothing overflows (the starting exponential of a direction with no states may be inf or
  /// 0, unused), and the relative error stays below 1e-13 (1 + gamma d^2) where e is a normal
  /// number, gamma d^2 < 708). A feature is the product of its axes' factors where the offsets'
  /// squared norm is within cutoff_radius^2 (as Evaluate selects them); callers that sum over
  /// features can sum row by row instead of listing them.
  struct AxisWindows {
    int first[D], n[D];
    double d[D][kMaxWindow], e[D][kMaxWindow];
  };
  /// False (and `out` unspecified) where s is not finite or has no state within the cut-off on
  /// some axis (then it has no features; true does not promise one). No allocation.
  bool Windows(const Vec<D>& s, AxisWindows* out) const;
  /// Visits the features at s row by row along axis 0, for sums that share a row's other factors:
  /// row(start, lo, hi, e_rest, rest) for each row holding features, whose states are the grid
  /// indices start + i for i in [lo, hi] (also the indices into windows->d[0] and ->e[0]), with
  /// the other axes' factor e_rest and offsets rest (rest[0] = 0). The features are exactly those
  /// Evaluate lists (the same cut-off test per state). False where Windows is (no row visited);
  /// true may still visit none. No allocation.
  template <class Row>
  bool ForEachRow(const Vec<D>& s, AxisWindows* windows, Row&& row) const;

 private:
  RbfGridSpec<D> spec_;
  int size_ = 0;
  int window_ = 0;
  double truncation_ = 0;
  double step_factor_ = 0;    ///< exp(-gamma spacing^2)
  double step_factor_2_ = 0;  ///< exp(-2 gamma spacing^2)
};

template <int D>
template <class Row>
bool RbfGrid<D>::ForEachRow(const Vec<D>& s, AxisWindows* windows, Row&& row) const {
  AxisWindows& w = *windows;
  if (!Windows(s, &w)) return false;
  const double cut2 = spec_.cutoff_radius * spec_.cutoff_radius;
  const auto& counts = spec_.counts;
  const double* d = w.d[0];
  // A row's states within the cut-off form one run of i (d falls with i, so d^2 first falls, then
  // rises): trim both ends by the test Evaluate applies per state.
  const auto visit = [&](int start, double rest2, double e_rest, const Vec<D>& rest) {
    int lo = 0, hi = w.n[0] - 1;
    while (lo <= hi && d[lo] * d[lo] + rest2 > cut2) ++lo;
    while (hi >= lo && d[hi] * d[hi] + rest2 > cut2) --hi;
    if (lo <= hi) row(start, lo, hi, e_rest, rest);
  };
  if constexpr (D == 2) {
    for (int j = 0; j < w.n[1]; ++j) {
      const double dy = w.d[1][j];
      if (dy * dy > cut2) continue;
      visit((w.first[1] + j) * counts[0] + w.first[0], dy * dy, w.e[1][j], Vec<2>(0, dy));
    }
  } else {
    for (int l = 0; l < w.n[2]; ++l) {
      const double dz = w.d[2][l];
      if (dz * dz > cut2) continue;
      for (int j = 0; j < w.n[1]; ++j) {
        const double dy = w.d[1][j];
        const double dyz2 = dy * dy + dz * dz;
        if (dyz2 > cut2) continue;
        visit(((w.first[2] + l) * counts[1] + w.first[1] + j) * counts[0] + w.first[0], dyz2,
              w.e[1][j] * w.e[2][l], Vec<3>(0, dy, dz));
      }
    }
  }
  return true;
}

// Derivatives from RbfFeatures (gamma g, offset r_t = s - c_t):
//   d phi_t / ds = -2 g phi_t r_t,   d^2 phi_t / ds^2 = phi_t (4 g^2 r_t r_t' - 2 g I).

}  // namespace foresight::imitation
