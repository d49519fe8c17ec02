#include "models/occupancy/bhm.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "core/error.h"

namespace foresight::occupancy {

BhmLearner::BhmLearner(HingeGrid grid, const FastBhmConfig& config)
    : grid_(std::move(grid)), config_(config) {
  const int t = grid_.size();
  FS_THROW_UNLESS(t <= 4096, "full BHM: ", t, " features (", grid_.Describe(),
                  ") is too many for a dense covariance; use at most 4096 (a coarser grid)");
  mean_ = Eigen::VectorXd::Constant(t, config.prior_mean);
  covariance_ = Eigen::MatrixXd::Identity(t, t) * config.prior_variance;
  precision_ = Eigen::MatrixXd::Identity(t, t) / config.prior_variance;
}

void BhmLearner::Bounds() {
  const SparseFeatures& f = features_;
  for (std::size_t n = 0; n < f.count.size(); ++n) {
    const int* idx = &f.index[n * f.stride];
    const double* phi = &f.value[n * f.stride];
    double quad = 0, m = 0;
    for (int i = 0; i < f.count[n]; ++i) {
      m += phi[i] * mean_[idx[i]];
      for (int j = 0; j < f.count[n]; ++j) quad += phi[i] * covariance_(idx[i], idx[j]) * phi[j];
    }
    z_[n] = std::sqrt(std::max(0.0, quad) + m * m);
  }
}

void BhmLearner::Update(const Eigen::Ref<const Eigen::Matrix2Xd>& xy,
                        const std::uint8_t* occupied) {
  const auto n = static_cast<std::size_t>(xy.cols());
  if (n == 0) return;
  features_.Compute(grid_, xy);
  const SparseFeatures& f = features_;
  z_.resize(n);
  if (config_.bound_init == BoundInit::kOne) {
    std::fill(z_.begin(), z_.end(), 1.0);
  } else {
    Bounds();
  }
  const Eigen::MatrixXd prior_precision = precision_;
  const Eigen::VectorXd prior_info = prior_precision * mean_;
  for (int it = 0; it < config_.em_iterations; ++it) {
    if (it > 0) Bounds();
    precision_ = prior_precision;
    Eigen::VectorXd info = prior_info;
    for (std::size_t p = 0; p < n; ++p) {
      const int* idx = &f.index[p * f.stride];
      const double* phi = &f.value[p * f.stride];
      const double two_lambda = 2.0 * JaakkolaLambda(z_[p]);
      const double target = occupied[p] ? 0.5 : -0.5;
      for (int i = 0; i < f.count[p]; ++i) {
        info[idx[i]] += target * phi[i];
        for (int j = 0; j < f.count[p]; ++j)
          precision_(idx[i], idx[j]) += two_lambda * phi[i] * phi[j];
      }
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(precision_);
    FS_THROW_UNLESS(llt.info() == Eigen::Success,
                    "full BHM: posterior precision is not positive definite");
    mean_ = llt.solve(info);
    covariance_ = llt.solve(Eigen::MatrixXd::Identity(grid_.size(), grid_.size()));
  }
}

HingeMap BhmLearner::ToMap() const {
  HingeWeights w;
  w.mean = mean_;
  w.covariance = covariance_;
  return HingeMap(HingeMapKind::kBhm, grid_, std::move(w), config_.prior_mean,
                  config_.prior_variance);
}

}  // namespace foresight::occupancy
