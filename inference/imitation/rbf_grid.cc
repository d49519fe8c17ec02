#include "inference/imitation/rbf_grid.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace foresight::imitation {
namespace {

constexpr long kMaxStates = 1L << 22;

}  // namespace

template <int D>
RbfGrid<D>::RbfGrid(const RbfGridSpec<D>& spec, const std::string& source) : spec_(spec) {
  FS_THROW_UNLESS(spec.lower.allFinite(), source, ": grid lower corner (", spec.lower.transpose(),
                  ") is not finite");
  FS_THROW_UNLESS(std::isfinite(spec.spacing) && spec.spacing > 0, source, ": grid spacing ",
                  spec.spacing, " must be positive and finite");
  FS_THROW_UNLESS(std::isfinite(spec.gamma) && spec.gamma > 0, source, ": kernel gamma ",
                  spec.gamma, " must be positive and finite");
  FS_THROW_UNLESS(std::isfinite(spec.cutoff_radius) && spec.cutoff_radius > 0, source,
                  ": cutoff_radius ", spec.cutoff_radius, " must be positive and finite");
  long size = 1;
  for (int a = 0; a < D; ++a) {
    FS_THROW_UNLESS(spec.counts[a] >= 1 && spec.counts[a] <= kMaxStates, source, ": grid count ",
                    spec.counts[a], " on axis ", a, " must be from 1 to ", kMaxStates);
    size *= spec.counts[a];
    FS_THROW_UNLESS(size <= kMaxStates, source, ": grid has more than ", kMaxStates,
                    " inducing states");
  }
  // The factors' recurrence (Windows) steps by exp(-gamma spacing^2): keep it far from underflow.
  FS_THROW_UNLESS(spec.gamma * spec.spacing * spec.spacing <= 300, source,
                  ": gamma spacing^2 = ", spec.gamma * spec.spacing * spec.spacing,
                  " exceeds 300 (neighbouring features differ by more than exp(-300)); use a "
                  "smaller gamma or spacing");
  const double ratio = spec.cutoff_radius / spec.spacing;
  FS_THROW_UNLESS(ratio < kMaxWindow / 2, source, ": cutoff_radius / spacing = ", ratio,
                  " is too large (window of more than ", kMaxWindow, " states per axis)");
  window_ = 2 * static_cast<int>(std::floor(ratio)) + 1;
  long window_states = 1;
  for (int a = 0; a < D; ++a) window_states *= window_;
  FS_THROW_UNLESS(window_states <= RbfFeatures<D>::kCapacity, source, ": the cut-off window holds ",
                  window_states, " inducing states (cutoff_radius ", spec.cutoff_radius,
                  ", spacing ", spec.spacing, "); at most ", RbfFeatures<D>::kCapacity,
                  " are supported");
  size_ = static_cast<int>(size);
  truncation_ = std::exp(-spec.gamma * spec.cutoff_radius * spec.cutoff_radius);
  step_factor_ = std::exp(-spec.gamma * spec.spacing * spec.spacing);
  step_factor_2_ = step_factor_ * step_factor_;
}

template <int D>
RbfGridSpec<D> RbfGrid<D>::Covering(const Vec<D>& lo, const Vec<D>& hi, double margin,
                                    double spacing, double gamma, double cutoff_radius) {
  FS_THROW_UNLESS(lo.allFinite() && hi.allFinite() && (hi.array() >= lo.array()).all(),
                  "rbf grid: covering box [", lo.transpose(), "] to [", hi.transpose(),
                  "] is not a finite box");
  FS_THROW_UNLESS(std::isfinite(margin) && margin >= 0, "rbf grid: margin ", margin,
                  " must be finite and non-negative");
  FS_THROW_UNLESS(std::isfinite(spacing) && spacing > 0, "rbf grid: spacing ", spacing,
                  " must be positive and finite");
  RbfGridSpec<D> spec;
  spec.lower = lo.array() - margin;
  spec.spacing = spacing;
  spec.gamma = gamma;
  spec.cutoff_radius = cutoff_radius;
  for (int a = 0; a < D; ++a) {
    const double cells = std::ceil((hi[a] - lo[a] + 2 * margin) / spacing - 1e-9);
    FS_THROW_UNLESS(cells < static_cast<double>(kMaxStates), "rbf grid: ", cells, " cells on axis ",
                    a, " are too many");
    spec.counts[a] = static_cast<int>(std::max(0.0, cells)) + 1;
  }
  return spec;
}

template <int D>
Vec<D> RbfGrid<D>::Centre(int t) const {
  Vec<D> c;
  for (int a = 0; a < D; ++a) {
    c[a] = spec_.lower[a] + spec_.spacing * (t % spec_.counts[a]);
    t /= spec_.counts[a];
  }
  return c;
}

template <int D>
bool RbfGrid<D>::Windows(const Vec<D>& s, AxisWindows* out) const {
  const double h = spec_.spacing, ratio = spec_.cutoff_radius / spec_.spacing;
  const double g = spec_.gamma;
  for (int a = 0; a < D; ++a) {
    // Not finite or absurdly far: no features (also keeps the casts below defined).
    if (!(std::abs(s[a]) < 1e12)) return false;
    const double f = (s[a] - spec_.lower[a]) / h;
    const double lo = std::max(0.0, std::ceil(f - ratio));
    const double hi = std::min(static_cast<double>(spec_.counts[a] - 1), std::floor(f + ratio));
    if (!(hi >= lo)) return false;
    const int first = static_cast<int>(lo), n = static_cast<int>(hi) - first + 1;
    out->first[a] = first;
    out->n[a] = n;
    double* d = out->d[a];
    double* e = out->e[a];
    for (int i = 0; i < n; ++i) d[i] = s[a] - (spec_.lower[a] + h * (first + i));
    // d falls with i; from the state nearest s (|d_c| <= h / 2 inside the grid) outward.
    const int c = std::clamp(static_cast<int>(std::lround(f)) - first, 0, n - 1);
    e[c] = std::exp(-g * d[c] * d[c]);
    // Upward d_{i} = d_{i-1} - h: e_i = e_{i-1} exp(-g h^2) exp(2 g h d_{i-1}); downward the sign
    // of the last factor's exponent flips.
    const double up0 = std::exp(2 * g * h * d[c]);
    double q = up0;
    for (int i = c + 1; i < n; ++i) {
      e[i] = e[i - 1] * (step_factor_ * q);
      q *= step_factor_2_;
    }
    q = 1 / up0;
    for (int i = c - 1; i >= 0; --i) {
      e[i] = e[i + 1] * (step_factor_ * q);
      q *= step_factor_2_;
    }
  }
  return true;
}

// The feature list, row by row as ForEachRow visits them (one definition of which states count).
template <int D>
void RbfGrid<D>::Evaluate(const Vec<D>& s, RbfFeatures<D>* out) const {
  out->count = 0;
  AxisWindows w;
  int k = 0;
  ForEachRow(s, &w, [&](int start, int lo, int hi, double e_rest, const Vec<D>& rest) {
    for (int i = lo; i <= hi; ++i) {
      out->index[k] = start + i;
      out->phi[k] = w.e[0][i] * e_rest;
      out->offset[k] = rest;
      out->offset[k][0] = w.d[0][i];
      ++k;
    }
  });
  out->count = k;
}

template class RbfGrid<2>;
template class RbfGrid<3>;

}  // namespace foresight::imitation
