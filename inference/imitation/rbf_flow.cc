#include "inference/imitation/rbf_flow.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace foresight::imitation {

template <int D>
RbfFlow<D>::RbfFlow(RbfGrid<D> grid, Eigen::MatrixXd weights, FlowSettings<D> settings,
                    const std::string& source)
    : grid_(std::move(grid)), weights_(std::move(weights)), settings_(settings) {
  FS_THROW_UNLESS(weights_.allFinite(), source, ": weights are not finite");
  FS_THROW_UNLESS(std::isfinite(settings_.time) && settings_.time > 0, source, ": flow time ",
                  settings_.time, " must be positive and finite");
  FS_THROW_UNLESS(settings_.steps >= 1, source, ": flow steps ", settings_.steps,
                  " must be at least 1");
  FS_THROW_UNLESS(settings_.segments >= 1 && settings_.segments <= settings_.steps, source,
                  ": flow segments ", settings_.segments,
                  " must be in [1, steps = ", settings_.steps, "]");
  FS_THROW_UNLESS(weights_.rows() == settings_.segments * grid_.size() && weights_.cols() == D,
                  source, ": weights are ", weights_.rows(), " x ", weights_.cols(), ", expected ",
                  settings_.segments * grid_.size(), " x ", D,
                  " (segments x inducing states, dimension)");
  rows_ = weights_.transpose();
  const double max_row = weights_.size() ? weights_.rowwise().norm().maxCoeff() : 0.0;
  discontinuity_ = 2 * grid_.truncation() * max_row;
}

template <int D>
FlowWorkspace<D> RbfFlow<D>::MakeWorkspace() const {
  return {};
}

// V = sum_t W_t phi_t,  DV = sum_t W_t (d phi_t / ds)' = -2 g sum_t (W_t phi_t) r_t', summed row
// by row of the separable window (RbfGrid::ForEachRow): a row shares every factor but e_0, so
//   sum_i W_i phi_i = e_rest sum_i W_i e_0i,  sum_i W_i phi_i r_i' = e_rest [sum_i W_i e_0i d_0i,
//   (sum_i W_i e_0i) rest_1, ...].
// The workspace's feature list is not used.
template <int D>
Vec<D> RbfFlow<D>::Field(const Vec<D>& s, FlowWorkspace<D>* /*ws*/, Mat<D>* jacobian,
                         int segment) const {
  typename RbfGrid<D>::AxisWindows w;
  const double* d = w.d[0];
  const double* e = w.e[0];
  const double* cols = rows_.data() + static_cast<std::ptrdiff_t>(segment) * grid_.size() * D;
  Vec<D> v = Vec<D>::Zero();
  Mat<D> dv = Mat<D>::Zero();
  const bool with_jacobian = jacobian != nullptr;
  grid_.ForEachRow(s, &w, [&](int start, int lo, int hi, double e_rest, const Vec<D>& rest) {
    Vec<D> a0 = Vec<D>::Zero(), a1 = Vec<D>::Zero();  // sum W e, sum W e d along the row
    for (int i = lo; i <= hi; ++i) {
      const Eigen::Map<const Vec<D>> wi(cols + static_cast<std::ptrdiff_t>(start + i) * D);
      const Vec<D> a = e[i] * wi;
      a0 += a;
      if (with_jacobian) a1 += d[i] * a;
    }
    a0 *= e_rest;
    v += a0;
    if (with_jacobian) {
      dv.col(0) += e_rest * a1;
      for (int b = 1; b < D; ++b) dv.col(b) += rest[b] * a0;
    }
  });
  if (with_jacobian) *jacobian = (-2.0 * grid_.gamma()) * dv;
  return v;
}

template <int D>
Vec<D> RbfFlow<D>::Forward(const Vec<D>& x, FlowWorkspace<D>* ws, Mat<D>* jacobian) const {
  const double h = settings_.time / settings_.steps;
  Vec<D> s = x;
  if (jacobian == nullptr) {
    for (int k = 0; k < settings_.steps; ++k)
      s += h * Field(s, ws, nullptr, SegmentOfStep(settings_, k));
    return s;
  }
  Mat<D> j = Mat<D>::Identity(), dv;
  for (int k = 0; k < settings_.steps; ++k) {
    const Vec<D> v = Field(s, ws, &dv, SegmentOfStep(settings_, k));
    j = (Mat<D>::Identity() + h * dv) * j;
    s += h * v;
  }
  *jacobian = j;
  return s;
}

template <int D>
bool RbfFlow<D>::Inverse(const Vec<D>& z, FlowWorkspace<D>* ws, Vec<D>* x, double tolerance,
                         int max_iterations) const {
  const double h = settings_.time / settings_.steps;
  return detail::InvertEulerMap<D>(
      z, settings_.steps, h,
      [&](const Vec<D>& s, int k) { return Field(s, ws, nullptr, SegmentOfStep(settings_, k)); },
      tolerance, h * discontinuity_, max_iterations, x);
}

std::string InvertibilityReport::Describe() const {
  std::ostringstream os;
  os << (ok ? "invertible" : "NOT invertible") << " on " << points
     << " points: max round-trip error " << max_roundtrip_error
     << ", min Euler-step determinant det(I + h DV) " << min_step_determinant << ", "
     << failed_points << " points whose inverse did not converge";
  return os.str();
}

template <int D>
InvertibilityReport CheckInvertible(const RbfFlow<D>& flow,
                                    const Eigen::Matrix<double, D, -1>& points, double tolerance) {
  InvertibilityReport r;
  r.points = static_cast<int>(points.cols());
  FlowWorkspace<D> ws = flow.MakeWorkspace();
  const double h = flow.settings().time / flow.settings().steps;
  Mat<D> dv;
  for (Eigen::Index p = 0; p < points.cols(); ++p) {
    Vec<D> s = points.col(p);
    for (int k = 0; k < flow.settings().steps; ++k) {
      const Vec<D> v = flow.Field(s, &ws, &dv, SegmentOfStep(flow.settings(), k));
      const double det = (Mat<D>::Identity() + h * dv).determinant();
      if (!(det >= r.min_step_determinant)) r.min_step_determinant = det;  // NaN too
      s += h * v;
    }
    Vec<D> back;
    if (!s.allFinite() || !flow.Inverse(s, &ws, &back)) {
      ++r.failed_points;
      continue;
    }
    const double err = (back - points.col(p)).norm();
    if (!(err <= r.max_roundtrip_error)) r.max_roundtrip_error = err;
  }
  r.ok = r.failed_points == 0 && r.max_roundtrip_error <= tolerance && r.min_step_determinant > 0;
  return r;
}

template <int D>
ImitationSystem<D>::ImitationSystem(RbfFlow<D> flow, Vec<D> goal, double speed)
    : flow_(std::move(flow)), goal_(goal), speed_(speed) {
  FS_THROW_UNLESS(goal_.allFinite(), "imitation system: goal (", goal_.transpose(),
                  ") is not finite");
  FS_THROW_UNLESS(std::isfinite(speed_) && speed_ > 0, "imitation system: speed ", speed_,
                  " must be positive and finite");
  FlowWorkspace<D> ws = flow_.MakeWorkspace();
  goal_image_ = flow_.Forward(goal_, &ws);
  FS_THROW_UNLESS(goal_image_.allFinite(),
                  "imitation system: the flow maps the goal to a "
                  "non-finite point");
}

// f_i(x) = -speed J^-1 (z - z_e) / ||z - z_e||, z = psi(x); solved with J (errata ch 8).
template <int D>
Vec<D> ImitationSystem<D>::Velocity(const Vec<D>& x, FlowWorkspace<D>* ws, Vec<D>* z) const {
  Mat<D> j;
  const Vec<D> image = flow_.Forward(x, ws, &j);
  if (z != nullptr) *z = image;
  const Vec<D> d = image - goal_image_;
  const double n = d.norm();
  if (n == 0) return Vec<D>::Zero();
  return j.partialPivLu().solve((-speed_ / n) * d);
}

template class RbfFlow<2>;
template class RbfFlow<3>;
template class ImitationSystem<2>;
template class ImitationSystem<3>;
template InvertibilityReport CheckInvertible<2>(const RbfFlow<2>&,
                                                const Eigen::Matrix<double, 2, -1>&, double);
template InvertibilityReport CheckInvertible<3>(const RbfFlow<3>&,
                                                const Eigen::Matrix<double, 3, -1>&, double);

}  // namespace foresight::imitation
