#include "inference/constrained/component.h"

#include <cmath>

#include "core/error.h"

namespace foresight::constrained {

namespace {

void CheckShapes(const char* what, const Eigen::MatrixXd& mean, const Eigen::VectorXd& log_u) {
  FS_THROW_UNLESS(mean.cols() == 2, what, ": mean must have 2 columns, got ", mean.rows(), " x ",
                  mean.cols());
  FS_THROW_UNLESS(mean.rows() >= 1, what, ": mean has no rows (basis size 0)");
  FS_THROW_UNLESS(log_u.size() == mean.rows(), what, ": log_u has ", log_u.size(),
                  " entries, the mean has ", mean.rows(), " rows");
}

}  // namespace

Eigen::VectorXd ComponentParams::ToVector() const {
  CheckShapes("ComponentParams::ToVector", mean, log_u);
  FS_THROW_UNLESS(chol_v(0, 0) > 0 && chol_v(1, 1) > 0,
                  "ComponentParams::ToVector: chol_v needs a positive diagonal, got (",
                  chol_v(0, 0), ", ", chol_v(1, 1), ")");
  const int m = basis();
  Eigen::VectorXd theta(size());
  theta.head(2 * m) = mean.reshaped();  // column-major vec(M)
  theta.segment(2 * m, m) = log_u;
  theta[3 * m] = std::log(chol_v(0, 0));
  theta[3 * m + 1] = chol_v(1, 0);
  theta[3 * m + 2] = std::log(chol_v(1, 1));
  return theta;
}

ComponentParams ComponentParams::FromVector(const Eigen::VectorXd& theta, int basis) {
  FS_THROW_UNLESS(basis >= 1, "ComponentParams::FromVector: basis must be >= 1, got ", basis);
  FS_THROW_UNLESS(theta.size() == 3 * basis + 3, "ComponentParams::FromVector: theta has ",
                  theta.size(), " entries, expected 3 * basis + 3 = ", 3 * basis + 3);
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    FS_THROW_UNLESS(std::isfinite(theta[i]), "ComponentParams::FromVector: theta[", i,
                    "] is not finite (", theta[i], ")");
  }
  const int m = basis;
  ComponentParams c;
  c.mean = theta.head(2 * m).reshaped(m, 2);
  c.log_u = theta.segment(m * 2, m);
  c.chol_v << std::exp(theta[3 * m]), 0, theta[3 * m + 1], std::exp(theta[3 * m + 2]);
  return c;
}

void ComponentGradient::Resize(int basis) {
  FS_THROW_UNLESS(basis >= 1, "ComponentGradient::Resize: basis must be >= 1, got ", basis);
  mean.setZero(basis, 2);
  log_u.setZero(basis);
  chol_v.setZero();
}

Eigen::VectorXd ComponentGradient::ToVector(const ComponentParams& at) const {
  CheckShapes("ComponentGradient::ToVector", mean, log_u);
  FS_THROW_UNLESS(mean.rows() == at.basis(), "ComponentGradient::ToVector: gradient basis ",
                  mean.rows(), " differs from the parameters' basis ", at.basis());
  const int m = at.basis();
  Eigen::VectorXd g(3 * m + 3);
  g.head(2 * m) = mean.reshaped();
  g.segment(2 * m, m) = log_u;
  // L_ii = exp(theta_i), so dC/dtheta_i = dC/dL_ii * L_ii.
  g[3 * m] = chol_v(0, 0) * at.chol_v(0, 0);
  g[3 * m + 1] = chol_v(1, 0);
  g[3 * m + 2] = chol_v(1, 1) * at.chol_v(1, 1);
  return g;
}

}  // namespace foresight::constrained
