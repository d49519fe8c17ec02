#include "inference/navigation/crowd_forecast.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace foresight::nav {

namespace {
double LargestEigenvalue(const Eigen::Matrix2d& c) {
  const double tr = 0.5 * (c(0, 0) + c(1, 1));
  const double det = c(0, 0) * c(1, 1) - 0.25 * (c(0, 1) + c(1, 0)) * (c(0, 1) + c(1, 0));
  return tr + std::sqrt(std::max(0.0, tr * tr - det));
}
}  // namespace

void CrowdForecast::Reserve(int max_pedestrians, int steps, int components) {
  const auto cells = static_cast<std::size_t>(max_pedestrians) * steps * components;
  alpha_.reserve(static_cast<std::size_t>(max_pedestrians) * components);
  mean_.reserve(cells);
  cov_.reserve(cells);
  reach_.reserve(cells);
}

void CrowdForecast::FromPredictions(const std::vector<TrajectoryDistribution>& dists, int n,
                                    int steps, double dt) {
  FS_THROW_UNLESS(n >= 0 && static_cast<std::size_t>(n) <= dists.size(), "CrowdForecast: ", n,
                  " pedestrians but ", dists.size(), " predictions");
  n_ = n;
  steps_ = steps;
  r_ = n > 0 ? dists[0].components() : 1;
  const auto cells = static_cast<std::size_t>(n) * steps * r_;
  alpha_.resize(static_cast<std::size_t>(n) * r_);
  mean_.resize(cells);
  cov_.resize(cells);
  reach_.resize(cells);
  for (int i = 0; i < n; ++i) {
    const TrajectoryDistribution& d = dists[static_cast<std::size_t>(i)];
    for (int r = 0; r < r_; ++r) alpha_[static_cast<std::size_t>(i * r_ + r)] = d.alpha(r);
    for (int k = 1; k <= steps; ++k)
      for (int r = 0; r < r_; ++r) {
        const std::size_t j = Index(i, k, r);
        d.Position(k * dt, r, &mean_[j], &cov_[j]);
        reach_[j] = std::sqrt(LargestEigenvalue(cov_[j]));
      }
  }
}

void CrowdForecast::FromCurrentPositions(const Eigen::Ref<const Eigen::Matrix2Xd>& positions,
                                         int steps) {
  n_ = static_cast<int>(positions.cols());
  steps_ = steps;
  r_ = 1;
  const auto cells = static_cast<std::size_t>(n_) * steps;
  alpha_.assign(static_cast<std::size_t>(n_), 1.0);
  mean_.resize(cells);
  cov_.resize(cells);
  reach_.resize(cells);
  for (int i = 0; i < n_; ++i)
    for (int k = 1; k <= steps; ++k) {
      const std::size_t j = Index(i, k, 0);
      mean_[j] = positions.col(i);
      cov_[j].setZero();
      reach_[j] = 0.0;
    }
}

bool CrowdForecast::Collides(int k, const Eigen::Vector2d& x, double radius,
                             const ChanceThreshold& threshold) const {
  const double c = threshold.c();
  const int kc = commit_steps_ > 0 ? std::min(k, commit_steps_) : k;  // step of the covariance
  for (int n = 0; n < n_; ++n) {
    if (r_ == 1) {
      const std::size_t j = Index(n, k, 0), jc = Index(n, kc, 0);
      const Eigen::Vector2d d = x - mean_[j];
      // Quick reject: a' Sigma a <= lambda_max, so no collision when ||d|| >= radius + c sqrt(2
      // lambda_max).
      const double outer = radius + std::max(0.0, c) * M_SQRT2 * reach_[jc];
      if (d.squaredNorm() >= outer * outer) continue;
      if (threshold.Exceeds(d, cov_[jc], radius)) return true;
    } else {
      // sum_r alpha_r bound_r <= max_r bound_r: when no component's bound exceeds epsilon (the
      // erf-free test, with the quick reject of one component), neither does the mixture's.
      bool any = false;
      for (int r = 0; r < r_ && !any; ++r) {
        const std::size_t j = Index(n, k, r), jc = Index(n, kc, r);
        const Eigen::Vector2d d = x - mean_[j];
        const double outer = radius + std::max(0.0, c) * M_SQRT2 * reach_[jc];
        any = d.squaredNorm() < outer * outer && threshold.Exceeds(d, cov_[jc], radius);
      }
      if (!any) continue;
      double bound = 0.0;
      for (int r = 0; r < r_; ++r) {
        const std::size_t j = Index(n, k, r), jc = Index(n, kc, r);
        const Eigen::Vector2d d = x - mean_[j];
        // Components farther than radius + 6 sigma contribute < 1e-9: skipped.
        const double outer = radius + 6.0 * reach_[jc];
        if (d.squaredNorm() >= outer * outer) continue;
        bound += alpha_[static_cast<std::size_t>(n * r_ + r)] *
                 CollisionProbabilityBound(x, mean_[j], cov_[jc], radius);
      }
      if (bound > threshold.epsilon()) return true;
    }
  }
  return false;
}

double CrowdForecast::MaxBound(int k, const Eigen::Vector2d& x, double radius) const {
  double best = 0.0;
  for (int n = 0; n < n_; ++n) {
    double bound = 0.0;
    for (int r = 0; r < r_; ++r) {
      const std::size_t j = Index(n, k, r);
      bound += alpha_[static_cast<std::size_t>(n * r_ + r)] *
               CollisionProbabilityBound(x, mean_[j], cov_[j], radius);
    }
    best = std::max(best, bound);
  }
  return best;
}

double CrowdForecast::UnionBound(int k, const Eigen::Vector2d& x, double radius) const {
  double sum = 0.0;
  for (int n = 0; n < n_; ++n)
    for (int r = 0; r < r_; ++r) {
      const std::size_t j = Index(n, k, r);
      const double outer = radius + 6.0 * reach_[j];
      // Far components add < 1e-9; a non-finite one (a broken prediction) is ignored, as in
      // Collides().
      if (!((x - mean_[j]).squaredNorm() < outer * outer)) continue;
      sum += alpha_[static_cast<std::size_t>(n * r_ + r)] *
             CollisionProbabilityBound(x, mean_[j], cov_[j], radius);
    }
  return sum;
}

}  // namespace foresight::nav
