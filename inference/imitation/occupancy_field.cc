#include "inference/imitation/occupancy_field.h"

#include <cmath>

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

// f = b + sum a_t,  grad f = -2 g sum a_t r_t,  Hess f = 4 g^2 sum a_t r_t r_t' - 2 g (f - b) I.
// The workspace is not used: the sums are taken row by row (SumFeatures).
template <int D>
void OccupancyField<D>::Evaluate(const Vec<D>& s, RbfFeatures<D>* /*ws*/, bool with_hessian,
                                 OccupancyValue<D>* out) const {
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
  FeatureSums<D> f;  // summed as Evaluate does: the same p to the bit
  SumFeatures(grid_, weights_, s, false, &f);
  return Sigmoid(bias_ + f.sum);
}

template class OccupancyField<2>;
template class OccupancyField<3>;

}  // namespace foresight::imitation
