#include "core/matrix_normal.h"

#include <Eigen/Dense>
#include <cmath>

#include "core/error.h"

namespace foresight {

double MatrixNormal::LogPdf(const Eigen::MatrixXd& w) const {
  const int m = rows();
  FS_THROW_UNLESS(w.rows() == m && w.cols() == 2, "MatrixNormal::LogPdf: W is ", w.rows(), "x",
                  w.cols(), ", expected ", m, "x2");
  const Eigen::MatrixXd d = w - mean;
  // A = L_U^-1 D, B = A L_V^-T  =>  tr[V^-1 D' U^-1 D] = ||B||_F^2.
  const Eigen::MatrixXd a = chol_u.triangularView<Eigen::Lower>().solve(d);
  const Eigen::MatrixXd b = chol_v.triangularView<Eigen::Lower>().solve(a.transpose()).transpose();
  const double log_det_u = 2.0 * chol_u.diagonal().array().log().sum();
  const double log_det_v = 2.0 * chol_v.diagonal().array().log().sum();
  return -0.5 * b.squaredNorm() - m * std::log(2.0 * M_PI) - 0.5 * m * log_det_v - log_det_u;
}

void MatrixNormal::Position(const Eigen::VectorXd& phi, Eigen::Vector2d* mu,
                            Eigen::Matrix2d* cov) const {
  *mu = mean.transpose() * phi;
  const double s = (chol_u.transpose() * phi).squaredNorm();  // phi' U phi
  *cov = s * (chol_v * chol_v.transpose());
}

Eigen::MatrixXd MatrixNormal::Sample(std::mt19937_64* rng) const {
  std::normal_distribution<double> n01;
  Eigen::MatrixXd z(rows(), 2);
  for (Eigen::Index i = 0; i < z.size(); ++i) z.data()[i] = n01(*rng);
  return mean + chol_u.triangularView<Eigen::Lower>() * z * chol_v.transpose();
}

double LogSumExp(const Eigen::VectorXd& v) {
  const double mx = v.maxCoeff();
  if (!std::isfinite(mx)) return mx;
  return mx + std::log((v.array() - mx).exp().sum());
}

double MatrixNormalMixture::LogPdf(const Eigen::MatrixXd& w) const {
  FS_THROW_UNLESS(weights.size() == components.size() && !weights.empty(),
                  "MatrixNormalMixture: weights and components differ in size");
  Eigen::VectorXd terms(static_cast<Eigen::Index>(weights.size()));
  for (std::size_t r = 0; r < weights.size(); ++r)
    terms[static_cast<Eigen::Index>(r)] = std::log(weights[r]) + components[r].LogPdf(w);
  return LogSumExp(terms);
}

double SquaredMahalanobis2(const Eigen::Vector2d& x, const Eigen::Vector2d& mu,
                           const Eigen::Matrix2d& cov) {
  const double det = cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(1, 0);
  const Eigen::Vector2d d = x - mu;
  return (d[0] * (cov(1, 1) * d[0] - cov(0, 1) * d[1]) +
          d[1] * (-cov(1, 0) * d[0] + cov(0, 0) * d[1])) /
         det;
}

double LogGaussian2(const Eigen::Vector2d& x, const Eigen::Vector2d& mu,
                    const Eigen::Matrix2d& cov) {
  const double det = cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(1, 0);
  return -0.5 * SquaredMahalanobis2(x, mu, cov) - std::log(2.0 * M_PI) - 0.5 * std::log(det);
}

}  // namespace foresight
