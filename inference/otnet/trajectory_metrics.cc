#include "inference/otnet/trajectory_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "inference/imitation/metrics.h"

namespace foresight::otnet {
namespace {

constexpr double kLog2Pi = 1.8378770664093454836;  // log(2 pi)

void CheckNonEmpty(const Eigen::MatrixX2d& t, const char* what, const char* name) {
  FS_THROW_UNLESS(t.rows() >= 1, what, ": trajectory ", name, " has no points");
}

/// max_{p in a} min_{q in b} ||p - q|| (brute force).
double DirectedHausdorff(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b) {
  double worst_sq = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    double best_sq = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < b.rows(); ++j)
      best_sq = std::min(best_sq, (a.row(i) - b.row(j)).squaredNorm());
    worst_sq = std::max(worst_sq, best_sq);
  }
  return std::sqrt(worst_sq);
}

double Distance(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b, TrajectoryDistance d) {
  switch (d) {
    case TrajectoryDistance::kHausdorff:
      return TrajectoryHausdorff(a, b);
    case TrajectoryDistance::kFrechet:
      return TrajectoryFrechet(a, b);
  }
  Fail("MeanMinimumDistance: unknown TrajectoryDistance ", static_cast<int>(d));
}

}  // namespace

Eigen::MatrixX2d ResampleUniform(const Eigen::MatrixX2d& waypoints, int count) {
  const Eigen::Index n = waypoints.rows();
  FS_THROW_UNLESS(n >= 1, "ResampleUniform: the trajectory has no waypoints");
  FS_THROW_UNLESS(count >= 2, "ResampleUniform: count must be >= 2, got ", count);
  for (Eigen::Index i = 0; i < n; ++i)
    FS_THROW_UNLESS(waypoints.row(i).allFinite(), "ResampleUniform: waypoint ", i, " (",
                    waypoints(i, 0), ", ", waypoints(i, 1), ") is not finite");
  Eigen::MatrixX2d out(count, 2);
  if (n == 1) {
    out.rowwise() = waypoints.row(0);
    return out;
  }
  // Waypoint i sits at tau = i / (n - 1); sample k at tau_k = k / (count - 1), linear in between.
  for (int k = 0; k < count; ++k) {
    const double s = static_cast<double>(k) * static_cast<double>(n - 1) / (count - 1);
    const Eigen::Index i = std::min<Eigen::Index>(static_cast<Eigen::Index>(s), n - 2);
    const double f = s - static_cast<double>(i);
    out.row(k) = (1.0 - f) * waypoints.row(i) + f * waypoints.row(i + 1);
  }
  out.row(0) = waypoints.row(0);  // the ends exactly
  out.row(count - 1) = waypoints.row(n - 1);
  return out;
}

double TrajectoryHausdorff(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b) {
  CheckNonEmpty(a, "TrajectoryHausdorff", "a");
  CheckNonEmpty(b, "TrajectoryHausdorff", "b");
  return std::max(DirectedHausdorff(a, b), DirectedHausdorff(b, a));
}

double TrajectoryFrechet(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b) {
  CheckNonEmpty(a, "TrajectoryFrechet", "a");
  CheckNonEmpty(b, "TrajectoryFrechet", "b");
  // imitation::DiscreteFrechet takes [d x n] paths, one point per column.
  return imitation::DiscreteFrechet(a.transpose(), b.transpose());
}

double MeanMinimumDistance(const std::vector<Eigen::MatrixX2d>& generated,
                           const std::vector<Eigen::MatrixX2d>& truth, TrajectoryDistance d) {
  FS_THROW_UNLESS(!generated.empty(), "MeanMinimumDistance: no generated trajectories");
  FS_THROW_UNLESS(!truth.empty(), "MeanMinimumDistance: no ground-truth trajectories");
  // MTD = min_i D(xi_gen, xi_i) (thesis ch 6, "Dataset and Metrics"), averaged over xi_gen.
  double sum = 0;
  for (const Eigen::MatrixX2d& g : generated) {
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::MatrixX2d& t : truth) best = std::min(best, Distance(g, t, d));
    sum += best;
  }
  return sum / static_cast<double>(generated.size());
}

double AverageNegativeLogLikelihood(const PerTimeDensity& density, const Eigen::MatrixX2d& truth) {
  const Eigen::Index q_count = density.weights.size();
  FS_THROW_UNLESS(q_count >= 1, "AverageNegativeLogLikelihood: the density has no components");
  FS_THROW_UNLESS(density.means.size() == static_cast<size_t>(q_count) &&
                      density.covs.size() == static_cast<size_t>(q_count),
                  "AverageNegativeLogLikelihood: ", q_count, " weights but ", density.means.size(),
                  " means and ", density.covs.size(), " covariances");
  const Eigen::Index l_count = density.times();
  FS_THROW_UNLESS(l_count >= 1, "AverageNegativeLogLikelihood: the density has no times");
  FS_THROW_UNLESS(truth.rows() == l_count, "AverageNegativeLogLikelihood: truth has ", truth.rows(),
                  " points, the density has ", l_count, " times");
  FS_THROW_UNLESS(truth.allFinite(), "AverageNegativeLogLikelihood: truth is not finite");
  double weight_sum = 0;
  for (Eigen::Index q = 0; q < q_count; ++q) {
    const double a = density.weights[q];
    FS_THROW_UNLESS(a >= 0 && std::isfinite(a), "AverageNegativeLogLikelihood: weight ", q, " is ",
                    a, " (must be >= 0)");
    weight_sum += a;
    FS_THROW_UNLESS(density.means[q].rows() == l_count && density.means[q].allFinite(),
                    "AverageNegativeLogLikelihood: means of component ", q, " have ",
                    density.means[q].rows(), " rows (expected ", l_count, ", finite)");
    FS_THROW_UNLESS(density.covs[q].rows() == l_count && density.covs[q].cols() == 3,
                    "AverageNegativeLogLikelihood: covariances of component ", q, " are ",
                    density.covs[q].rows(), " x ", density.covs[q].cols(), ", expected ", l_count,
                    " x 3");
  }
  FS_THROW_UNLESS(std::abs(weight_sum - 1.0) <= 1e-6,
                  "AverageNegativeLogLikelihood: weights sum to ", weight_sum, ", not 1");

  double total = 0;
  for (Eigen::Index l = 0; l < l_count; ++l) {
    // log p_l(x) = log sum_q alpha_q N(x; mu_q, Sigma_q), by log-sum-exp over the components.
    double max_term = -std::numeric_limits<double>::infinity();
    double scaled_sum = 0;  // sum_q exp(log_term_q - max_term)
    for (Eigen::Index q = 0; q < q_count; ++q) {
      const double vx = density.covs[q](l, 0), cxy = density.covs[q](l, 1);
      const double vy = density.covs[q](l, 2);
      const double det = vx * vy - cxy * cxy;
      FS_THROW_UNLESS(vx > 0 && det > 0 && std::isfinite(det),
                      "AverageNegativeLogLikelihood: covariance of component ", q, " at time ", l,
                      " (var_x ", vx, ", cov_xy ", cxy, ", var_y ", vy,
                      ") is not positive definite");
      if (density.weights[q] == 0) continue;
      const double dx = truth(l, 0) - density.means[q](l, 0);
      const double dy = truth(l, 1) - density.means[q](l, 1);
      // (x - mu)' Sigma^-1 (x - mu) with the closed-form 2 x 2 inverse.
      const double maha = (vy * dx * dx - 2.0 * cxy * dx * dy + vx * dy * dy) / det;
      const double log_term =
          std::log(density.weights[q]) - kLog2Pi - 0.5 * std::log(det) - 0.5 * maha;
      if (!(log_term > -std::numeric_limits<double>::infinity())) continue;  // adds nothing
      if (log_term > max_term) {
        scaled_sum = scaled_sum * std::exp(max_term - log_term) + 1.0;
        max_term = log_term;
      } else {
        scaled_sum += std::exp(log_term - max_term);
      }
    }
    // A zero density (only for absurdly far points) gives an infinite NLL, reported as such.
    total += max_term + std::log(scaled_sum);
  }
  return -total / static_cast<double>(l_count);
}

PerTimeDensity FitPerTimeGaussian(const std::vector<Eigen::MatrixX2d>& trajectories,
                                  double variance_floor) {
  FS_THROW_UNLESS(!trajectories.empty(), "FitPerTimeGaussian: no trajectories");
  FS_THROW_UNLESS(variance_floor > 0 && std::isfinite(variance_floor),
                  "FitPerTimeGaussian: variance_floor must be > 0 and finite, got ",
                  variance_floor);
  const Eigen::Index l_count = trajectories.front().rows();
  FS_THROW_UNLESS(l_count >= 1, "FitPerTimeGaussian: trajectory 0 has no points");
  for (size_t k = 0; k < trajectories.size(); ++k) {
    FS_THROW_UNLESS(trajectories[k].rows() == l_count, "FitPerTimeGaussian: trajectory ", k,
                    " has ", trajectories[k].rows(), " points, trajectory 0 has ", l_count,
                    " (resample first)");
    FS_THROW_UNLESS(trajectories[k].allFinite(), "FitPerTimeGaussian: trajectory ", k,
                    " is not finite");
  }
  const double n = static_cast<double>(trajectories.size());
  Eigen::MatrixX2d mean = Eigen::MatrixX2d::Zero(l_count, 2);
  for (const Eigen::MatrixX2d& t : trajectories) mean += t;
  mean /= n;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(l_count, 3);
  for (const Eigen::MatrixX2d& t : trajectories) {
    const Eigen::MatrixX2d d = t - mean;
    cov.col(0) += d.col(0).cwiseAbs2();
    cov.col(1) += d.col(0).cwiseProduct(d.col(1));
    cov.col(2) += d.col(1).cwiseAbs2();
  }
  cov /= n;  // biased (maximum-likelihood) covariance, as a Gaussian fit to the samples
  cov.col(0).array() += variance_floor;
  cov.col(2).array() += variance_floor;
  PerTimeDensity density;
  density.weights = Eigen::VectorXd::Ones(1);
  density.means.push_back(std::move(mean));
  density.covs.push_back(std::move(cov));
  return density;
}

}  // namespace foresight::otnet
