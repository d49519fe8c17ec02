#include "models/occupancy/fast_bhm.h"

#include <cmath>

#include "core/error.h"

namespace foresight::occupancy {

double JaakkolaLambda(double z) {
  const double a = std::abs(z);
  if (a < 1e-4) return 0.125 - a * a / 96.0;  // Taylor: (1/8) - z^2/96 + O(z^4)
  return (1.0 / (1.0 + std::exp(-a)) - 0.5) / (2.0 * a);
}

void SparseFeatures::Compute(const HingeGrid& grid, const Eigen::Ref<const Eigen::Matrix2Xd>& xy) {
  stride = grid.max_active();
  const auto n = static_cast<std::size_t>(xy.cols());
  count.resize(n);
  if (index.size() < n * stride) {
    index.resize(n * stride);
    value.resize(n * stride);
  }
  for (std::size_t i = 0; i < n; ++i) {
    count[i] = grid.Features(xy(0, i), xy(1, i), &index[i * stride], &value[i * stride]);
  }
}

FastBhmLearner::FastBhmLearner(HingeGrid grid, const FastBhmConfig& config)
    : grid_(std::move(grid)), config_(config) {
  mean_ = Eigen::VectorXd::Constant(grid_.size(), config.prior_mean);
  variance_ = Eigen::VectorXd::Constant(grid_.size(), config.prior_variance);
  acc_precision_.assign(grid_.size(), 0.0);
  acc_data_.assign(grid_.size(), 0.0);
  is_touched_.assign(grid_.size(), 0);
}

FastBhmLearner::FastBhmLearner(const HingeMap& start, const FastBhmConfig& config)
    : FastBhmLearner(start.grid(), config) {
  FS_THROW_UNLESS(start.kind() == HingeMapKind::kFastBhm,
                  "Fast-BHM training can only continue from a ", kFastBhmType, " map, not ",
                  start.model_type());
  mean_ = start.weights().mean;
  variance_ = start.weights().variance;
}

void FastBhmLearner::BoundsFromPosterior(const SparseFeatures& f) {
  const bool exact = config_.m_step == MStepForm::kExact;
  for (std::size_t n = 0; n < f.count.size(); ++n) {
    const int* idx = &f.index[n * f.stride];
    const double* phi = &f.value[n * f.stride];
    double var = 0, m = 0, printed = 0;
    for (int i = 0; i < f.count[n]; ++i) {
      const double p2 = phi[i] * phi[i];
      const double mu = mean_[idx[i]];
      var += p2 * variance_[idx[i]];
      m += phi[i] * mu;
      printed += p2 * mu * mu;
    }
    z_[n] = std::sqrt(exact ? var + m * m : var + printed);
  }
}

void FastBhmLearner::Update(const Eigen::Ref<const Eigen::Matrix2Xd>& xy,
                            const std::uint8_t* occupied) {
  const auto n = static_cast<std::size_t>(xy.cols());
  if (n == 0) return;
  features_.Compute(grid_, xy);
  const SparseFeatures& f = features_;
  z_.resize(n);
  if (config_.bound_init == BoundInit::kOne) {
    std::fill(z_.begin(), z_.end(), 1.0);
  } else {
    BoundsFromPosterior(f);
  }
  // The prior of this scan is the current posterior (sequential BHM).
  touched_.clear();
  for (std::size_t p = 0; p < n; ++p) {
    const int* idx = &f.index[p * f.stride];
    for (int i = 0; i < f.count[p]; ++i) {
      if (!is_touched_[idx[i]]) {
        is_touched_[idx[i]] = 1;
        touched_.push_back(idx[i]);
      }
    }
  }
  prior_precision_.resize(touched_.size());
  prior_info_.resize(touched_.size());
  for (std::size_t j = 0; j < touched_.size(); ++j) {
    const int t = touched_[j];
    prior_precision_[j] = 1.0 / variance_[t];
    prior_info_[j] = mean_[t] * prior_precision_[j];
  }
  for (int it = 0; it < config_.em_iterations; ++it) {
    if (it > 0) BoundsFromPosterior(f);
    for (const int t : touched_) acc_precision_[t] = acc_data_[t] = 0.0;
    for (std::size_t p = 0; p < n; ++p) {
      const int* idx = &f.index[p * f.stride];
      const double* phi = &f.value[p * f.stride];
      const double two_lambda = 2.0 * JaakkolaLambda(z_[p]);
      const double target = occupied[p] ? 0.5 : -0.5;
      for (int i = 0; i < f.count[p]; ++i) {
        acc_precision_[idx[i]] += two_lambda * phi[i] * phi[i];
        acc_data_[idx[i]] += target * phi[i];
      }
    }
    for (std::size_t j = 0; j < touched_.size(); ++j) {
      const int t = touched_[j];
      const double s2 = 1.0 / (prior_precision_[j] + acc_precision_[t]);
      variance_[t] = s2;
      mean_[t] = s2 * (prior_info_[j] + acc_data_[t]);
    }
  }
  for (const int t : touched_) is_touched_[t] = 0;
}

HingeMap FastBhmLearner::ToMap() const {
  HingeWeights w;
  w.mean = mean_;
  w.variance = variance_;
  return HingeMap(HingeMapKind::kFastBhm, grid_, std::move(w), config_.prior_mean,
                  config_.prior_variance);
}

}  // namespace foresight::occupancy
