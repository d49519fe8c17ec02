#include "inference/constrained/prediction_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace foresight::constrained {

namespace {

void CheckFinite(const char* what, const Eigen::Ref<const Eigen::MatrixX2d>& x) {
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    FS_THROW_UNLESS(std::isfinite(x(i, 0)) && std::isfinite(x(i, 1)), what, ": row ", i,
                    " is not finite (", x(i, 0), ", ", x(i, 1), ")");
  }
}

}  // namespace

PredictionScores ScorePrediction(const TrajectoryDistribution& d,
                                 const Eigen::Ref<const Eigen::MatrixX2d>& truth, double dt) {
  const Eigen::Index f = truth.rows();
  FS_THROW_UNLESS(f >= 1, "ScorePrediction: the ground truth has no rows");
  FS_THROW_UNLESS(std::isfinite(dt) && dt > 0, "ScorePrediction: dt must be > 0, got ", dt);
  FS_THROW_UNLESS(d.components() >= 1, "ScorePrediction: the distribution has no component");
  CheckFinite("ScorePrediction: truth", truth);
  PredictionScores s;
  const double inv_f = 1.0 / static_cast<double>(f);
  // Nearest component by ADE of its mean path.
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < d.components(); ++r) {
    double ade = 0, fde = 0;
    for (Eigen::Index i = 0; i < f; ++i) {
      Eigen::Vector2d mu;
      Eigen::Matrix2d cov;
      d.Position(static_cast<double>(i + 1) * dt, r, &mu, &cov);
      const double e = (mu - truth.row(i).transpose()).norm();
      ade += e * inv_f;
      if (i + 1 == f) fde = e;
    }
    if (ade < best || r == 0) {
      best = ade;
      s.ade_nearest = ade;
      s.fde_nearest = fde;
      s.nearest = r;
    }
  }
  for (Eigen::Index i = 0; i < f; ++i) {
    const double t = static_cast<double>(i + 1) * dt;
    const Eigen::Vector2d x = truth.row(i).transpose();
    const double e = (d.MeanPosition(t) - x).norm();
    s.ade_mixture += e * inv_f;
    if (i + 1 == f) s.fde_mixture = e;
    const double log_p = d.LogDensity(t, x);
    s.al += std::exp(log_p) * inv_f;
    s.anll -= log_p * inv_f;
  }
  return s;
}

PredictionScores ScorePoints(const Eigen::Ref<const Eigen::MatrixX2d>& predicted,
                             const Eigen::Ref<const Eigen::MatrixX2d>& truth) {
  FS_THROW_UNLESS(predicted.rows() == truth.rows(), "ScorePoints: ", predicted.rows(),
                  " predicted points for ", truth.rows(), " true ones");
  FS_THROW_UNLESS(truth.rows() >= 1, "ScorePoints: no points");
  CheckFinite("ScorePoints: truth", truth);
  PredictionScores s;
  const Eigen::Index f = truth.rows();
  for (Eigen::Index i = 0; i < f; ++i) {
    s.ade_nearest += (predicted.row(i) - truth.row(i)).norm() / static_cast<double>(f);
  }
  s.fde_nearest = (predicted.row(f - 1) - truth.row(f - 1)).norm();
  s.ade_mixture = s.ade_nearest;
  s.fde_mixture = s.fde_nearest;
  s.al = s.anll = std::numeric_limits<double>::quiet_NaN();
  return s;
}

Eigen::MatrixX2d ConstantVelocity(const Eigen::Ref<const Eigen::MatrixX2d>& past, int f) {
  FS_THROW_UNLESS(past.rows() >= 2, "ConstantVelocity: need >= 2 observed points, got ",
                  past.rows());
  FS_THROW_UNLESS(f >= 1, "ConstantVelocity: f (future steps) must be >= 1, got ", f);
  const Eigen::RowVector2d last = past.row(past.rows() - 1);
  const Eigen::RowVector2d step = last - past.row(past.rows() - 2);
  Eigen::MatrixX2d out(f, 2);
  for (int i = 0; i < f; ++i) out.row(i) = last + static_cast<double>(i + 1) * step;
  return out;
}

double Percentile(std::vector<double> v, double q) {
  FS_THROW_UNLESS(q >= 0 && q <= 100, "Percentile: q must be in [0, 100], got ", q);
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < v.size(); ++i) {
    FS_THROW_UNLESS(!std::isnan(v[i]), "Percentile: sample value ", i, " is NaN");
  }
  std::sort(v.begin(), v.end());
  const double pos = q / 100.0 * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  const double w = pos - static_cast<double>(lo);
  return w == 0 ? v[lo] : v[lo] + w * (v[hi] - v[lo]);
}

}  // namespace foresight::constrained
