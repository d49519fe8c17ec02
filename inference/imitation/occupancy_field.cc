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

// With a_t = w_t phi_t:  f = b + sum a_t,  grad f = -2 g sum a_t r_t,
// Hess f = 4 g^2 sum a_t r_t r_t' - 2 g (f - b) I.
template <int D>
void OccupancyField<D>::Evaluate(const Vec<D>& s, RbfFeatures<D>* ws, bool with_hessian,
                                 OccupancyValue<D>* out) const {
  grid_.Evaluate(s, ws);
  const double g = grid_.gamma();
  double sum = 0;
  Vec<D> first = Vec<D>::Zero();
  Mat<D> second = Mat<D>::Zero();
  for (int i = 0; i < ws->count; ++i) {
    const double a = weights_[ws->index[i]] * ws->phi[i];
    const Vec<D>& r = ws->offset[i];
    sum += a;
    first += a * r;
    if (with_hessian) second.noalias() += (a * r) * r.transpose();
  }
  const double p = Sigmoid(bias_ + sum);
  const double dp = p * (1 - p);
  const Vec<D> grad_f = (-2 * g) * first;
  out->p = p;
  out->gradient = dp * grad_f;
  if (with_hessian) {
    const Mat<D> hess_f = (4 * g * g) * second - (2 * g * sum) * Mat<D>::Identity();
    out->hessian = dp * ((1 - 2 * p) * grad_f * grad_f.transpose() + hess_f);
  } else {
    out->hessian.setZero();
  }
}

template <int D>
double OccupancyField<D>::Probability(const Vec<D>& s, RbfFeatures<D>* ws) const {
  grid_.Evaluate(s, ws);
  double sum = 0;  // summed as Evaluate does: the same p to the bit
  for (int i = 0; i < ws->count; ++i) sum += weights_[ws->index[i]] * ws->phi[i];
  return Sigmoid(bias_ + sum);
}

template class OccupancyField<2>;
template class OccupancyField<3>;

}  // namespace foresight::imitation
