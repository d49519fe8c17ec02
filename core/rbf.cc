#include "core/rbf.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "core/error.h"

namespace foresight {

TimeBasis::TimeBasis(int num_centres, double t_begin, double t_end, double gamma) : gamma_(gamma) {
  FS_THROW_UNLESS(num_centres >= 1, "TimeBasis: num_centres must be >= 1, got ", num_centres);
  FS_THROW_UNLESS(gamma > 0 && std::isfinite(gamma), "TimeBasis: gamma must be > 0, got ", gamma);
  FS_THROW_UNLESS(t_end >= t_begin, "TimeBasis: t_end ", t_end, " < t_begin ", t_begin);
  if (num_centres == 1)
    centres_ = Eigen::VectorXd::Constant(1, 0.5 * (t_begin + t_end));
  else
    centres_ = Eigen::VectorXd::LinSpaced(num_centres, t_begin, t_end);
}

TimeBasis::TimeBasis(Eigen::VectorXd centres, double gamma)
    : centres_(std::move(centres)), gamma_(gamma) {
  FS_THROW_UNLESS(centres_.size() >= 1, "TimeBasis: need at least one centre");
  FS_THROW_UNLESS(gamma > 0 && std::isfinite(gamma), "TimeBasis: gamma must be > 0, got ", gamma);
}

Eigen::VectorXd TimeBasis::Evaluate(double t) const {
  Eigen::VectorXd out(size());
  Evaluate(t, out);
  return out;
}

Eigen::MatrixXd TimeBasis::Design(const Eigen::VectorXd& times) const {
  Eigen::MatrixXd p(times.size(), size());
  for (Eigen::Index i = 0; i < times.size(); ++i) p.row(i) = Evaluate(times[i]).transpose();
  return p;
}

Eigen::MatrixXd TimeBasis::FitRidge(const Eigen::VectorXd& times, const Eigen::MatrixXd& points,
                                    double lambda) const {
  return RidgeProjector(*this, times, lambda).Fit(points);
}

RidgeProjector::RidgeProjector(const TimeBasis& basis, const Eigen::VectorXd& times,
                               double lambda) {
  FS_THROW_UNLESS(lambda >= 0, "ridge: lambda must be >= 0, got ", lambda);
  const Eigen::MatrixXd p = basis.Design(times);
  Eigen::MatrixXd gram = p.transpose() * p;
  gram.diagonal().array() += lambda;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(gram);
  FS_THROW_UNLESS(ldlt.info() == Eigen::Success && ldlt.isPositive(),
                  "ridge: normal equations are singular; increase lambda");
  solve_ = ldlt.solve(p.transpose());
}

}  // namespace foresight
