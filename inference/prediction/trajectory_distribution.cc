#include "inference/prediction/trajectory_distribution.h"

#include <cmath>

#include "core/error.h"

namespace foresight {

TrajectoryDistribution::TrajectoryDistribution(const TimeBasis& basis, int components)
    : basis_(basis) {
  const int m = basis.size();
  alpha_ = Eigen::VectorXd::Zero(components);
  mean_.assign(static_cast<std::size_t>(components), Eigen::MatrixXd::Zero(m, 2));
  chol_u_.assign(static_cast<std::size_t>(components), Eigen::MatrixXd::Zero(m, m));
  chol_v_.assign(static_cast<std::size_t>(components), Eigen::Matrix2d::Identity());
  phi_.resize(m);
  u_phi_.resize(m);
  z_.resize(m, 2);
  w_.resize(m, 2);
}

MatrixNormal TrajectoryDistribution::Component(int r) const {
  return MatrixNormal{mean(r), chol_u(r), chol_v(r)};
}

void TrajectoryDistribution::Position(double t, int r, Eigen::Vector2d* mu,
                                      Eigen::Matrix2d* cov) const {
  basis_.Evaluate(t, phi_);
  const auto k = static_cast<std::size_t>(r);
  *mu = origin_ + t * velocity_;
  for (int j = 0; j < basis_size(); ++j) *mu += phi_[j] * mean_[k].row(j).transpose();
  // phi' U phi = ||L_U' phi||^2 with L_U lower triangular.
  const int m = basis_size();
  double s = 0.0;
  for (int j = 0; j < m; ++j) {
    double acc = 0.0;
    for (int i = j; i < m; ++i) acc += chol_u_[k](i, j) * phi_[i];
    s += acc * acc;
  }
  const Eigen::Matrix2d& l = chol_v_[k];
  cov->noalias() = s * (l * l.transpose());
}

Eigen::Vector2d TrajectoryDistribution::MeanPosition(double t) const {
  basis_.Evaluate(t, phi_);
  Eigen::Vector2d out = origin_ + t * velocity_;
  for (int r = 0; r < components(); ++r)
    for (int j = 0; j < basis_size(); ++j)
      out += alpha_[r] * phi_[j] * mean_[static_cast<std::size_t>(r)].row(j).transpose();
  return out;
}

void TrajectoryDistribution::MixturePosition(double t, Eigen::Vector2d* mean,
                                             Eigen::Matrix2d* cov) const {
  mean->setZero();
  cov->setZero();
  Eigen::Vector2d mu_r;
  Eigen::Matrix2d cov_r;
  for (int r = 0; r < components(); ++r) {
    Position(t, r, &mu_r, &cov_r);
    *mean += alpha_[r] * mu_r;
    cov->noalias() += alpha_[r] * (cov_r + mu_r * mu_r.transpose());
  }
  cov->noalias() -= *mean * mean->transpose();
}

double TrajectoryDistribution::LogDensity(double t, const Eigen::Vector2d& x) const {
  double mx = -INFINITY;
  double terms[64];
  const int R = std::min(components(), 64);
  for (int r = 0; r < R; ++r) {
    Eigen::Vector2d mu;
    Eigen::Matrix2d cov;
    Position(t, r, &mu, &cov);
    terms[r] = std::log(alpha_[r]) + LogGaussian2(x, mu, cov);
    mx = std::max(mx, terms[r]);
  }
  if (!std::isfinite(mx)) return mx;
  double sum = 0.0;
  for (int r = 0; r < R; ++r) sum += std::exp(terms[r] - mx);
  return mx + std::log(sum);
}

void TrajectoryDistribution::SamplePath(
    const Eigen::Ref<const Eigen::VectorXd>& times, std::mt19937_64* rng,
    Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 2>> path) const {
  // Pick a component, then W = M + L_U Z L_V' with Z standard normal.
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  int r = 0;
  double u = u01(*rng), acc = 0.0;
  for (; r + 1 < components(); ++r) {
    acc += alpha_[r];
    if (u < acc) break;
  }
  const auto k = static_cast<std::size_t>(r);
  const int m = basis_size();
  for (int i = 0; i < m; ++i) z_(i, 0) = n01(*rng), z_(i, 1) = n01(*rng);
  for (int i = 0; i < m; ++i) {
    double a0 = 0.0, a1 = 0.0;  // (L_U Z)_i
    for (int j = 0; j <= i; ++j)
      a0 += chol_u_[k](i, j) * z_(j, 0), a1 += chol_u_[k](i, j) * z_(j, 1);
    const Eigen::Matrix2d& l = chol_v_[k];
    w_(i, 0) = mean_[k](i, 0) + a0 * l(0, 0);
    w_(i, 1) = mean_[k](i, 1) + a0 * l(1, 0) + a1 * l(1, 1);
  }
  for (Eigen::Index n = 0; n < times.size(); ++n) {
    basis_.Evaluate(times[n], phi_);
    Eigen::Vector2d o = origin_ + times[n] * velocity_;
    for (int j = 0; j < m; ++j) o += phi_[j] * w_.row(j).transpose();
    path.row(n) = o.transpose();
  }
}

void TrajectoryDistribution::SetComponent(int r, const Eigen::MatrixXd& mean,
                                          const Eigen::MatrixXd& chol_u,
                                          const Eigen::Matrix2d& chol_v) {
  const int m = basis_size();
  FS_THROW_UNLESS(r >= 0 && r < components(), "TrajectoryDistribution::SetComponent: component ", r,
                  " out of range [0, ", components(), ")");
  FS_THROW_UNLESS(mean.rows() == m && mean.cols() == 2,
                  "TrajectoryDistribution::SetComponent: mean is ", mean.rows(), " x ", mean.cols(),
                  ", expected ", m, " x 2");
  FS_THROW_UNLESS(chol_u.rows() == m && chol_u.cols() == m,
                  "TrajectoryDistribution::SetComponent: chol_u is ", chol_u.rows(), " x ",
                  chol_u.cols(), ", expected ", m, " x ", m);
  const auto k = static_cast<std::size_t>(r);
  mean_[k] = mean;
  chol_u_[k] = chol_u;
  chol_v_[k] = chol_v;
}

void TrajectoryDistribution::SetFrame(const Eigen::Vector2d& origin,
                                      const Eigen::Vector2d& velocity,
                                      const Eigen::VectorXd& alpha) {
  FS_THROW_UNLESS(alpha.size() == alpha_.size(), "TrajectoryDistribution::SetFrame: alpha has ",
                  alpha.size(), " entries, the distribution has ", alpha_.size(), " components");
  origin_ = origin;
  velocity_ = velocity;
  alpha_ = alpha;
}

}  // namespace foresight
