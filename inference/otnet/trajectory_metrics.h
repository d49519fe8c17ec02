#pragma once
/// Metrics of generated trajectory sets against the ground truth of a map (thesis ch 6, "Dataset
/// and Metrics"). Every trajectory is first resampled to L = 100 points at uniform normalised time
/// (ResampleUniform: linear interpolation between waypoints i / (n - 1), as the authors' script).
///
/// - Trajectory distances: the Euclidean Hausdorff distance max(h(a, b), h(b, a)) between the two
///   point sets, and the discrete Frechet distance (Eiter & Mannila; imitation/metrics.h).
/// - MTD (minimum trajectory distance) of a generated trajectory: min over the ground-truth
///   trajectories of the distance; a method's score on a map is the mean MTD over its generated
///   trajectories (the thesis's table). Coverage is the reverse: the mean over ground-truth
///   trajectories of the distance to the nearest generated one (penalises missed modes).
/// - ANLL: the mean over ground-truth trajectories and over the L uniform taus of
///   -log p_tau(xi(tau)), with p_tau the predicted per-time 2-D density (PerTimeDensity): for OTNet
///   sum_q alpha_q N(x; mu_q(tau), Sigma_q(tau)) with the component's exact marginal at tau (x and
///   y independent within a component, as the model); for baselines given as trajectory sets (k-NN,
///   the mean trajectory) a Gaussian per tau fitted to their trajectories (mean, 2 x 2 covariance
///   plus a variance floor), as the thesis does for k-NN.

#include <Eigen/Core>
#include <vector>

namespace foresight::otnet {

/// [n x 2] -> [count x 2] at uniform normalised time (n >= 1, count >= 2; a single waypoint is
/// repeated). Error on non-finite points.
Eigen::MatrixX2d ResampleUniform(const Eigen::MatrixX2d& waypoints, int count);

/// max(h(a, b), h(b, a)) between the point sets of two [n x 2] trajectories (brute force).
double TrajectoryHausdorff(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b);
/// Discrete Frechet distance of two [n x 2] trajectories.
double TrajectoryFrechet(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b);

enum class TrajectoryDistance { kHausdorff, kFrechet };

/// Mean over `generated` of min over `truth` of the distance (all already resampled). Error when
/// either set is empty.
double MeanMinimumDistance(const std::vector<Eigen::MatrixX2d>& generated,
                           const std::vector<Eigen::MatrixX2d>& truth, TrajectoryDistance d);

/// A per-time 2-D density at L fixed taus: a mixture of Gaussians per tau.
struct PerTimeDensity {
  Eigen::VectorXd weights;              ///< [Q], sum 1
  std::vector<Eigen::MatrixX2d> means;  ///< Q x [L x 2]
  std::vector<Eigen::MatrixXd> covs;    ///< Q x [L x 3]: (var_x, cov_xy, var_y) per tau
  int times() const { return means.empty() ? 0 : static_cast<int>(means.front().rows()); }
};

/// -1/L sum_l log p_l(truth_l) for one resampled ground-truth trajectory [L x 2] (log-sum-exp over
/// components). Error on a size mismatch or a non-positive-definite covariance.
double AverageNegativeLogLikelihood(const PerTimeDensity& density, const Eigen::MatrixX2d& truth);

/// The one-component density of a set of resampled trajectories ([L x 2] each, >= 1): per tau the
/// sample mean and the (biased) sample covariance plus variance_floor on the diagonal (> 0).
PerTimeDensity FitPerTimeGaussian(const std::vector<Eigen::MatrixX2d>& trajectories,
                                  double variance_floor);

}  // namespace foresight::otnet
