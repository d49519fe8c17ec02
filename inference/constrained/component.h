#pragma once
/// One matrix-normal component of a predicted trajectory distribution (thesis ch 7) in the
/// parametrisation the optimiser works in:
///   W in R^{m x 2} ~ MN(M, U, V),  U = diag(exp(log_u)),  V = L_V L_V' (L_V lower, positive
///   diagonal),
/// so the position at time t is N(M' phi(t), s(t)^2 V) with s(t)^2 = phi(t)' U phi(t)
/// (errata ch 5/7; core/matrix_normal.h). The optimiser's flat vector is
///   theta = [vec(M) column-major (2m); log_u (m); log L_V(0,0), L_V(1,0), log L_V(1,1)]  (3m + 3).

#include <Eigen/Core>

namespace foresight::constrained {

struct ComponentParams {
  Eigen::MatrixXd mean;                                  ///< M [m x 2]
  Eigen::VectorXd log_u;                                 ///< [m]
  Eigen::Matrix2d chol_v = Eigen::Matrix2d::Identity();  ///< L_V, lower, positive diagonal

  int basis() const { return static_cast<int>(mean.rows()); }
  int size() const { return 3 * basis() + 3; }  ///< length of theta
  Eigen::VectorXd ToVector() const;
  /// Error when theta's length is not 3m + 3 or it holds a non-finite value.
  static ComponentParams FromVector(const Eigen::VectorXd& theta, int basis);
};

/// Derivatives of a scalar with respect to the parameters (same shapes; chol_v's upper entry 0).
struct ComponentGradient {
  Eigen::MatrixXd mean;                              ///< [m x 2]
  Eigen::VectorXd log_u;                             ///< [m]
  Eigen::Matrix2d chol_v = Eigen::Matrix2d::Zero();  ///< d/dL_V (lower entries)
  void Resize(int basis);                            ///< zero-filled
  /// d/dtheta (3m + 3) by the chain rule (the diagonal of L_V enters as a log).
  Eigen::VectorXd ToVector(const ComponentParams& at) const;
};

}  // namespace foresight::constrained
