#include "models/span/span_data.h"

#include "core/ego_frame.h"
#include "core/error.h"

namespace foresight::span {

TimeBasis MakeFutureBasis(const TrajectoryBasisConfig& c, int predicted, double dt) {
  // Gaussian bumps centred only on [0, T] cannot follow a walk's linear growth near the ends
  // (about 15 cm error at t = T for m = 8); a margin of one second fixes it (tests/core/rbf_test).
  return TimeBasis(c.num_centres, -c.margin, predicted * dt + c.margin, c.gamma);
}

Samples MakeSamples(const WindowSet& w, const TimeBasis& basis, const TrajectoryBasisConfig& c,
                    bool rotate, bool residual) {
  const int p = w.observed, f = w.predicted, m = basis.size();
  const int first = c.anchor_at_origin ? 0 : 1;
  Eigen::VectorXd times(f + 1 - first);
  for (int k = first; k <= f; ++k) times[k - first] = k * w.seconds_per_step;
  const RidgeProjector ridge(basis, times, c.ridge_lambda);

  Samples s;
  s.inputs.resize(w.size(), 2 * p);
  s.targets.resize(w.size(), 2 * m);
  Eigen::MatrixXd points(times.size(), 2);
  for (int n = 0; n < w.size(); ++n) {
    const EgoFrame frame = EgoFrame::FromPast(
        p, [&](int i) { return w.Past(n, i); }, rotate);
    for (int i = 0; i < p; ++i) s.inputs.row(n).segment<2>(2 * i) = frame.ToEgo(w.Past(n, i));
    const Eigen::Vector2d v =
        residual ? Eigen::Vector2d(frame.rotation.transpose() *
                                   (w.Past(n, p - 1) - w.Past(n, p - 2)) / w.seconds_per_step)
                 : Eigen::Vector2d::Zero();
    if (first == 0) points.row(0).setZero();
    for (int k = 1; k <= f; ++k)
      points.row(k - first) = (frame.ToEgo(w.Future(n, k - 1)) - v * times[k - first]).transpose();
    const Eigen::MatrixXd wm = ridge.Fit(points);  // m x 2
    for (int j = 0; j < m; ++j) {
      s.targets(n, 2 * j) = wm(j, 0);
      s.targets(n, 2 * j + 1) = wm(j, 1);
    }
  }
  return s;
}

Samples Augment(const Samples& in, const AugmentConfig& a) {
  for (const double s : a.speed_scales)
    FS_THROW_UNLESS(s > 0 && std::abs(s - 1.0) > 1e-9, "augment.speed_scales: value ", s,
                    " (a scale must be positive and not 1; the data enter at scale 1 anyway)");
  const Eigen::Index n = in.inputs.rows();
  Samples out;
  out.inputs.resize(n * a.Copies(), in.inputs.cols());
  out.targets.resize(n * a.Copies(), in.targets.cols());
  Eigen::Index row = 0;
  const auto append = [&](double scale) {
    out.inputs.middleRows(row, n) = scale * in.inputs;
    out.targets.middleRows(row, n) = scale * in.targets;
    row += n;
  };
  append(1.0);
  for (const double s : a.speed_scales) append(s);
  if (a.mirror) {
    // Columns alternate x, y in both inputs (past points) and targets (rows of W).
    out.inputs.middleRows(row, row) = out.inputs.topRows(row);
    out.targets.middleRows(row, row) = out.targets.topRows(row);
    for (Eigen::Index c = 1; c < out.inputs.cols(); c += 2) out.inputs.col(c).tail(row) *= -1.0;
    for (Eigen::Index c = 1; c < out.targets.cols(); c += 2) out.targets.col(c).tail(row) *= -1.0;
  }
  return out;
}

}  // namespace foresight::span
