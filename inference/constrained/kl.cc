#include "inference/constrained/kl.h"

#include <Eigen/Dense>
#include <cmath>

#include "core/error.h"

namespace foresight::constrained {

namespace {

void CheckComponent(const char* which, const ComponentParams& c) {
  FS_THROW_UNLESS(c.mean.cols() == 2 && c.mean.rows() >= 1, "MatrixNormalKl: ", which,
                  ".mean must be m x 2 with m >= 1, got ", c.mean.rows(), " x ", c.mean.cols());
  FS_THROW_UNLESS(c.log_u.size() == c.mean.rows(), "MatrixNormalKl: ", which, ".log_u has ",
                  c.log_u.size(), " entries, the mean has ", c.mean.rows(), " rows");
  FS_THROW_UNLESS(c.chol_v(0, 0) > 0 && c.chol_v(1, 1) > 0, "MatrixNormalKl: ", which,
                  ".chol_v needs a positive diagonal, got (", c.chol_v(0, 0), ", ", c.chol_v(1, 1),
                  ")");
  FS_THROW_UNLESS(c.chol_v(0, 1) == 0, "MatrixNormalKl: ", which,
                  ".chol_v must be lower triangular, its (0, 1) entry is ", c.chol_v(0, 1));
}

}  // namespace

double MatrixNormalKl(const ComponentParams& p, const ComponentParams& p0,
                      ComponentGradient* gradient) {
  CheckComponent("p", p);
  CheckComponent("p0", p0);
  FS_THROW_UNLESS(p.basis() == p0.basis(), "MatrixNormalKl: p has basis ", p.basis(),
                  ", p0 has basis ", p0.basis());
  const int m = p.basis();
  const Eigen::Matrix2d& l = p.chol_v;
  const Eigen::Matrix2d& l0 = p0.chol_v;

  // tr(U0^-1 U) and ln(|U0| / |U|) for diagonal U = diag(exp(log_u)).
  const Eigen::ArrayXd u_ratio = (p.log_u - p0.log_u).array().exp();
  const double tr_u = u_ratio.sum();
  const double log_det_u = (p0.log_u - p.log_u).sum();
  // tr(V0^-1 V) = ||L0^-1 L||_F^2; ln |V| = 2 (ln L00 + ln L11).
  const Eigen::Matrix2d l0_inv_l = l0.triangularView<Eigen::Lower>().solve(l);
  const double tr_v = l0_inv_l.squaredNorm();
  const double log_det_v =
      2.0 * (std::log(l0(0, 0)) + std::log(l0(1, 1)) - std::log(l(0, 0)) - std::log(l(1, 1)));
  // tr(V0^-1 D' U0^-1 D) = ||L0^-1 D' U0^-1/2||_F^2, D = M - M0.
  const Eigen::MatrixXd d = p.mean - p0.mean;
  const Eigen::VectorXd u0_inv = (-p0.log_u).array().exp();
  const Eigen::MatrixXd dt_scaled = d.transpose() * u0_inv.array().sqrt().matrix().asDiagonal();
  const double mahalanobis = l0.triangularView<Eigen::Lower>().solve(dt_scaled).squaredNorm();

  // KL of vec(W) ~ N(vec(M), V kron U) (errata ch 5/7; Bishop 2006): tr(Sigma0^-1 Sigma) factors
  // into tr(V0^-1 V) tr(U0^-1 U) and |V kron U| = |V|^m |U|^2.
  const double kl = 0.5 * (tr_v * tr_u + mahalanobis - 2.0 * m + m * log_det_v + 2.0 * log_det_u);

  if (gradient != nullptr) {
    gradient->Resize(m);
    // d/dM 1/2 tr(V0^-1 D' U0^-1 D) = U0^-1 D V0^-1.
    const Eigen::Matrix2d v0_inv = (l0 * l0.transpose()).inverse();
    gradient->mean = u0_inv.asDiagonal() * d * v0_inv;
    // d/dlog_u_i: 1/2 tr_v u_i / u0_i - 1.
    gradient->log_u = (0.5 * tr_v * u_ratio - 1.0).matrix();
    // d/dL: tr_u V0^-1 L - m diag(1 / L_ii) (only the lower entries are parameters).
    Eigen::Matrix2d g = tr_u * v0_inv * l;
    g(0, 0) -= m / l(0, 0);
    g(1, 1) -= m / l(1, 1);
    g(0, 1) = 0.0;
    gradient->chol_v = g;
  }
  return kl;
}

}  // namespace foresight::constrained
