#include "inference/imitation/occupancy_field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "inference/mapping/hinge_map.h"

namespace foresight::imitation {

template <int D>
OccupancyField<D>::OccupancyField(RbfGrid<D> grid, Eigen::VectorXd weights, double bias,
                                  const std::string& source)
    : grid_(std::move(grid)), weights_(std::move(weights)), bias_(bias) {
  FS_THROW_UNLESS(weights_.size() == grid_.size(), source, ": ", weights_.size(),
                  " weights for a grid of ", grid_.size(), " inducing states");
  FS_THROW_UNLESS(weights_.allFinite(), source, ": weights are not finite");
  FS_THROW_UNLESS(std::isfinite(bias_), source, ": bias ", bias_, " is not finite");
}

template <int D>
OccupancyField<D> OccupancyField<D>::FromHingeMap(const occupancy::HingeMap& map) {
  if constexpr (D != 2) {
    Fail("occupancy field: a ", map.model_type(), " map is 2-D; cannot make a ", D, "-D field");
  } else {
    const HingeGridConfig& c = map.grid().config();
    RbfGridSpec<2> spec;
    spec.lower = Vec<2>(c.x_min, c.y_min);
    spec.counts = {map.grid().nx(), map.grid().ny()};
    spec.spacing = c.spacing;
    spec.gamma = c.gamma;
    spec.cutoff_radius = c.cutoff_radius;
    const std::string source = std::string("occupancy field from a ") + map.model_type() + " map";
    return OccupancyField<2>(RbfGrid<2>(spec, source), map.weights().mean, 0.0, source);
  }
}

template <int D>
std::unique_ptr<RbfFeatures<D>> OccupancyField<D>::MakeWorkspace() const {
  return std::make_unique<RbfFeatures<D>>();
}

namespace {
double Sigmoid(double f) {
  // Stable for large |f|: exp never overflows.
  if (f >= 0) return 1.0 / (1.0 + std::exp(-f));
  const double e = std::exp(f);
  return e / (1.0 + e);
}
}  // namespace

namespace {

// The sums over features of a_t = w_t phi_t, a_t r_t and a_t r_t r_t' (r_t = s - c_t), row by row
// of the separable window: along axis 0 a row's features share every factor but e_0, so
//   sum_i a = e_rest sum_i w_i e_0i,  sum_i a r_0 = e_rest sum_i w_i e_0i d_0i, ...
// three running sums per row instead of a feature list. The features are those RbfGrid::Evaluate
// lists (the same cut-off test); only the order of the additions differs.
template <int D>
struct FeatureSums {
  double sum = 0;                  // sum a
  Vec<D> first = Vec<D>::Zero();   // sum a r
  Mat<D> second = Mat<D>::Zero();  // sum a r r' (only when asked)
};

template <int D>
void SumFeatures(const RbfGrid<D>& grid, const Eigen::VectorXd& weights, const Vec<D>& s,
                 bool with_second, FeatureSums<D>* out) {
  typename RbfGrid<D>::AxisWindows w;
  const double* d = w.d[0];
  const double* e = w.e[0];
  const bool any =
      grid.ForEachRow(s, &w, [&](int start, int lo, int hi, double e_rest, const Vec<D>& rest) {
        const double* wt = weights.data() + start;
        double a0 = 0, a1 = 0, a2 = 0;  // sum w e, sum w e d, sum w e d^2 along the row
        if (with_second) {
          for (int i = lo; i <= hi; ++i) {
            const double a = wt[i] * e[i];
            a0 += a;
            a1 += a * d[i];
            a2 += a * d[i] * d[i];
          }
        } else {
          for (int i = lo; i <= hi; ++i) {
            const double a = wt[i] * e[i];
            a0 += a;
            a1 += a * d[i];
          }
        }
        a0 *= e_rest;
        a1 *= e_rest;
        out->sum += a0;
        out->first[0] += a1;
        for (int b = 1; b < D; ++b) out->first[b] += a0 * rest[b];
        if (with_second) {
          out->second(0, 0) += a2 * e_rest;
          for (int b = 1; b < D; ++b) {
            out->second(0, b) += a1 * rest[b];
            for (int c = b; c < D; ++c) out->second(b, c) += a0 * rest[b] * rest[c];
          }
        }
      });
  if (any && with_second)
    for (int b = 0; b < D; ++b)
      for (int c = b + 1; c < D; ++c) out->second(c, b) = out->second(b, c);
}

}  // namespace

/// Nodes over [lower, lower + spacing (n - 1)] per axis; node (i, j) at i + nx j holds the logit
/// and its derivatives scaled to a unit cell: f, h f_x, h f_y, h^2 f_xy.
struct LogitTable {
  Vec<2> lower = Vec<2>::Zero();
  double spacing = 0;
  int nx = 0, ny = 0;
  std::vector<std::array<double, 4>> nodes;
};

namespace {

/// The logit f and, scaled to the unit cell, its derivatives from the table at s: f, f_u, f_v,
/// f_uu, f_uv, f_vv (u = (x - x_i) / h). False where s is outside the table (or not finite).
bool TableLogit(const LogitTable& t, const Vec<2>& s, std::array<double, 6>* out) {
  const double x = (s[0] - t.lower[0]) / t.spacing, y = (s[1] - t.lower[1]) / t.spacing;
  if (!(x >= 0 && y >= 0 && x < t.nx - 1 && y < t.ny - 1)) return false;
  const int i = static_cast<int>(x), j = static_cast<int>(y);
  // Cubic Hermite basis on [0, 1]: values at 0 and 1 (h00, h01), slopes at 0 and 1 (h10, h11).
  const auto basis = [](double u, double* b, double* db, double* ddb) {
    const double u2 = u * u, u3 = u2 * u;
    b[0] = 1 - 3 * u2 + 2 * u3;
    b[1] = 3 * u2 - 2 * u3;
    b[2] = u - 2 * u2 + u3;
    b[3] = u3 - u2;
    db[0] = 6 * (u2 - u);
    db[1] = -db[0];
    db[2] = 1 - 4 * u + 3 * u2;
    db[3] = 3 * u2 - 2 * u;
    ddb[0] = 12 * u - 6;
    ddb[1] = -ddb[0];
    ddb[2] = 6 * u - 4;
    ddb[3] = 6 * u - 2;
  };
  double a[4], da[4], dda[4], b[4], db[4], ddb[4];
  basis(x - i, a, da, dda);
  basis(y - j, b, db, ddb);
  // C[p][q]: p, q in {corner 0, corner 1, slope at 0, slope at 1} along u and v.
  const std::array<double, 4>& n00 = t.nodes[static_cast<std::size_t>(i + t.nx * j)];
  const std::array<double, 4>& n10 = t.nodes[static_cast<std::size_t>(i + 1 + t.nx * j)];
  const std::array<double, 4>& n01 = t.nodes[static_cast<std::size_t>(i + t.nx * (j + 1))];
  const std::array<double, 4>& n11 = t.nodes[static_cast<std::size_t>(i + 1 + t.nx * (j + 1))];
  const double c[4][4] = {{n00[0], n01[0], n00[2], n01[2]},
                          {n10[0], n11[0], n10[2], n11[2]},
                          {n00[1], n01[1], n00[3], n01[3]},
                          {n10[1], n11[1], n10[3], n11[3]}};
  double cb[4], cdb[4], cddb[4];
  for (int p = 0; p < 4; ++p) {
    cb[p] = cdb[p] = cddb[p] = 0;
    for (int q = 0; q < 4; ++q) {
      cb[p] += c[p][q] * b[q];
      cdb[p] += c[p][q] * db[q];
      cddb[p] += c[p][q] * ddb[q];
    }
  }
  std::array<double, 6>& o = *out;
  o.fill(0);
  for (int p = 0; p < 4; ++p) {
    o[0] += a[p] * cb[p];
    o[1] += da[p] * cb[p];
    o[2] += a[p] * cdb[p];
    o[3] += dda[p] * cb[p];
    o[4] += da[p] * cdb[p];
    o[5] += a[p] * cddb[p];
  }
  return true;
}

}  // namespace

template <int D>
void OccupancyField<D>::Tabulate(double spacing, const std::string& source) {
  FS_THROW_UNLESS(std::isfinite(spacing) && spacing >= 0, source, ": table spacing ", spacing,
                  " must be zero (no table) or positive");
  if (spacing == 0) {
    table_.reset();
    return;
  }
  if constexpr (D != 2) {
    Fail(source, ": a table is built for 2-D fields only (this one is ", D, "-D)");
  } else {
    // The support: no feature reaches beyond the grid's box padded by the cut-off radius.
    const RbfGridSpec<2>& g = grid_.spec();
    auto t = std::make_shared<LogitTable>();
    t->spacing = spacing;
    t->lower = g.lower.array() - g.cutoff_radius;
    int n[2];
    for (int a = 0; a < 2; ++a) {
      const double extent = g.spacing * (g.counts[a] - 1) + 2 * g.cutoff_radius;
      n[a] = static_cast<int>(std::min(std::ceil(extent / spacing) + 1, 1e7));
    }
    const long nodes = static_cast<long>(n[0]) * n[1];
    FS_THROW_UNLESS(nodes <= (1L << 22), source, ": a table with spacing ", spacing, " would have ",
                    n[0], " x ", n[1], " nodes (at most 2^22)");
    t->nx = n[0];
    t->ny = n[1];
    t->nodes.resize(static_cast<std::size_t>(nodes));
    const double gm = grid_.gamma();
    for (int j = 0; j < t->ny; ++j)
      for (int i = 0; i < t->nx; ++i) {
        const Vec<2> s = t->lower + spacing * Vec<2>(i, j);
        FeatureSums<2> f;
        SumFeatures(grid_, weights_, s, true, &f);
        const Vec<2> grad = (-2 * gm) * f.first;
        t->nodes[static_cast<std::size_t>(i + t->nx * j)] = {
            bias_ + f.sum, spacing * grad[0], spacing * grad[1],
            spacing * spacing * 4 * gm * gm * f.second(0, 1)};
      }
    table_ = std::move(t);
  }
}

template <int D>
double OccupancyField<D>::table_spacing() const {
  return table_ ? table_->spacing : 0.0;
}

// f = b + sum a_t,  grad f = -2 g sum a_t r_t,  Hess f = 4 g^2 sum a_t r_t r_t' - 2 g (f - b) I.
// The workspace is not used: the sums are taken row by row (SumFeatures).
template <int D>
void OccupancyField<D>::Evaluate(const Vec<D>& s, RbfFeatures<D>* /*ws*/, bool with_hessian,
                                 OccupancyValue<D>* out) const {
  if constexpr (D == 2) {
    std::array<double, 6> t;
    if (table_ && TableLogit(*table_, s, &t)) {
      const double inv_h = 1 / table_->spacing;
      const double p = Sigmoid(t[0]);
      const double dp = p * (1 - p);
      const Vec<2> grad_f = inv_h * Vec<2>(t[1], t[2]);
      out->p = p;
      out->gradient = dp * grad_f;
      if (with_hessian) {
        Mat<2> hess_f;
        hess_f << t[3], t[4], t[4], t[5];
        hess_f *= inv_h * inv_h;
        out->hessian = dp * ((1 - 2 * p) * grad_f * grad_f.transpose() + hess_f);
      } else {
        out->hessian.setZero();
      }
      return;
    }
  }
  FeatureSums<D> f;
  SumFeatures(grid_, weights_, s, with_hessian, &f);
  const double g = grid_.gamma();
  const double p = Sigmoid(bias_ + f.sum);
  const double dp = p * (1 - p);
  const Vec<D> grad_f = (-2 * g) * f.first;
  out->p = p;
  out->gradient = dp * grad_f;
  if (with_hessian) {
    const Mat<D> hess_f = (4 * g * g) * f.second - (2 * g * f.sum) * Mat<D>::Identity();
    out->hessian = dp * ((1 - 2 * p) * grad_f * grad_f.transpose() + hess_f);
  } else {
    out->hessian.setZero();
  }
}

template <int D>
double OccupancyField<D>::Probability(const Vec<D>& s, RbfFeatures<D>* /*ws*/) const {
  if constexpr (D == 2) {
    std::array<double, 6> t;
    if (table_ && TableLogit(*table_, s, &t)) return Sigmoid(t[0]);
  }
  FeatureSums<D> f;  // summed as Evaluate does: the same p to the bit
  SumFeatures(grid_, weights_, s, false, &f);
  return Sigmoid(bias_ + f.sum);
}

template class OccupancyField<2>;
template class OccupancyField<3>;

}  // namespace foresight::imitation
