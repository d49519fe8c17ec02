#include "inference/imitation/rbf_grid.h"

#include <cmath>

#include "core/error.h"

namespace foresight::imitation {
namespace {

constexpr long kMaxStates = 1L << 22;
// Inducing states per axis inside the cut-off window (the separable factors' buffer).
constexpr int kMaxWindow = 64;

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
void RbfGrid<D>::Evaluate(const Vec<D>& s, RbfFeatures<D>* out) const {
  out->count = 0;
  const double h = spec_.spacing, ratio = spec_.cutoff_radius / spec_.spacing;
  const double g = spec_.gamma, cut2 = spec_.cutoff_radius * spec_.cutoff_radius;
  // Per axis: the window of states within the cut-off, their offsets and Gaussian factors.
  int first[D], n[D];
  double d[D][kMaxWindow], e[D][kMaxWindow];
  for (int a = 0; a < D; ++a) {
    // Not finite or absurdly far: no features (also keeps the casts below defined).
    if (!(std::abs(s[a]) < 1e12)) return;
    const double f = (s[a] - spec_.lower[a]) / h;
    const double lo = std::max(0.0, std::ceil(f - ratio));
    const double hi = std::min(static_cast<double>(spec_.counts[a] - 1), std::floor(f + ratio));
    if (!(hi >= lo)) return;
    first[a] = static_cast<int>(lo);
    n[a] = static_cast<int>(hi) - first[a] + 1;
    for (int i = 0; i < n[a]; ++i) {
      d[a][i] = s[a] - (spec_.lower[a] + h * (first[a] + i));
      e[a][i] = std::exp(-g * d[a][i] * d[a][i]);
    }
  }
  int k = 0;
  if constexpr (D == 2) {
    for (int j = 0; j < n[1]; ++j) {
      const double dy2 = d[1][j] * d[1][j];
      const int row = (first[1] + j) * spec_.counts[0] + first[0];
      for (int i = 0; i < n[0]; ++i) {
        if (d[0][i] * d[0][i] + dy2 > cut2) continue;
        out->index[k] = row + i;
        out->phi[k] = e[0][i] * e[1][j];
        out->offset[k] = Vec<D>(d[0][i], d[1][j]);
        ++k;
      }
    }
  } else {
    static_assert(D == 3, "RbfGrid supports D = 2 and 3");
    for (int l = 0; l < n[2]; ++l) {
      const double dz2 = d[2][l] * d[2][l];
      if (dz2 > cut2) continue;
      for (int j = 0; j < n[1]; ++j) {
        const double dyz2 = d[1][j] * d[1][j] + dz2;
        if (dyz2 > cut2) continue;
        const double eyz = e[1][j] * e[2][l];
        const int row =
            ((first[2] + l) * spec_.counts[1] + first[1] + j) * spec_.counts[0] + first[0];
        for (int i = 0; i < n[0]; ++i) {
          if (d[0][i] * d[0][i] + dyz2 > cut2) continue;
          out->index[k] = row + i;
          out->phi[k] = e[0][i] * eyz;
          out->offset[k] = Vec<D>(d[0][i], d[1][j], d[2][l]);
          ++k;
        }
      }
    }
  }
  out->count = k;
}

template class RbfGrid<2>;
template class RbfGrid<3>;

}  // namespace foresight::imitation
