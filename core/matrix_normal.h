#pragma once
/// Matrix-normal distributions over trajectory weights W [m x 2] and their mixtures.
///
/// Density (spec/errata.md, ch 5 and 7; the thesis prints U for U^-1 and swaps the determinant
/// exponents):
///   p(W) = exp(-1/2 tr[V^-1 (W-M)' U^-1 (W-M)]) / ((2 pi)^m |V|^{m/2} |U|),
/// equivalently vec(W) ~ N(vec(M), V kron U).  U = L_U L_U', V = L_V L_V' (lower Cholesky factors).
/// Position at time t (thesis eq. GPdef_eq_ch5): o(t) ~ N(M' phi(t), (phi(t)' U phi(t)) V).

#include <Eigen/Core>
#include <random>
#include <vector>

namespace foresight {

struct MatrixNormal {
  Eigen::MatrixXd mean;    ///< M [m x 2]
  Eigen::MatrixXd chol_u;  ///< L_U [m x m], lower triangular, positive diagonal
  Eigen::Matrix2d chol_v;  ///< L_V [2 x 2], lower triangular, positive diagonal

  int rows() const { return static_cast<int>(mean.rows()); }
  /// log p(W).
  double LogPdf(const Eigen::MatrixXd& w) const;
  /// Mean [2] and covariance [2 x 2] of the position at basis values phi(t) [m].
  void Position(const Eigen::VectorXd& phi, Eigen::Vector2d* mean, Eigen::Matrix2d* cov) const;
  /// W = M + L_U Z L_V' with Z standard normal.
  Eigen::MatrixXd Sample(std::mt19937_64* rng) const;
};

/// sum_r alpha_r MN(M_r, U_r, V_r).
struct MatrixNormalMixture {
  std::vector<double> weights;
  std::vector<MatrixNormal> components;
  double LogPdf(const Eigen::MatrixXd& w) const;
};

/// (x - mu)' Sigma^-1 (x - mu) for a 2-d Gaussian; x lies inside the k-sigma ellipse when it is
/// <= k^2, which a calibrated forecast gives with probability 1 - exp(-k^2 / 2) (39.3 % for k = 1,
/// 86.5 % for k = 2).
double SquaredMahalanobis2(const Eigen::Vector2d& x, const Eigen::Vector2d& mu,
                           const Eigen::Matrix2d& cov);

/// log N(x; mu, Sigma) for a 2-d Gaussian.
double LogGaussian2(const Eigen::Vector2d& x, const Eigen::Vector2d& mu,
                    const Eigen::Matrix2d& cov);

/// log(sum exp(v)) computed stably.
double LogSumExp(const Eigen::VectorXd& v);

}  // namespace foresight
