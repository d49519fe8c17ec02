#pragma once
/// Predicted pedestrian positions over the control horizon, tabulated once per control cycle:
/// for pedestrian n, step k (time k dt) and mixture component r, the Gaussian o ~ N(mean, cov) of
/// the predicted stochastic process (thesis ch 5, eq. GPdef; o(t) ~ N(M' phi(t), (phi' U phi) V)).
/// The collision test of eq. dynamicCheck is then a loop over tabulated 2 x 2 Gaussians.

#include <Eigen/Core>
#include <vector>

#include "inference/navigation/chance_bound.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::nav {

class CrowdForecast {
 public:
  /// Storage for up to `max_pedestrians` with `components` each over `steps` steps.
  void Reserve(int max_pedestrians, int steps, int components);

  /// Tabulates the predictions `dists[0..n)` at times k * dt, k = 1..steps.
  void FromPredictions(const std::vector<TrajectoryDistribution>& dists, int n, int steps,
                       double dt);
  /// Deterministic pedestrians standing still at `positions` [2 x n] (the reactive baseline's
  /// view).
  void FromCurrentPositions(const Eigen::Ref<const Eigen::Matrix2Xd>& positions, int steps);

  /// Steps k_c after which Collides() holds the covariance at k_c (0: never, the thesis).
  void set_commit_steps(int k_c) { commit_steps_ = k_c > 0 ? k_c : 0; }
  int commit_steps() const { return commit_steps_; }

  int pedestrians() const { return n_; }
  int steps() const { return steps_; }
  int components() const { return r_; }

  /// True when the probability bound of colliding with any pedestrian at step k (1-based) exceeds
  /// the threshold (eq. dynamicCheck). One component: the erf-free form of ChanceThreshold;
  /// mixtures: sum_r alpha_r bound_r > epsilon (a bound on the mixture probability). With a
  /// commitment of k_c steps (set_commit_steps), a step k > k_c is tested with the mean at k and
  /// the covariance at k_c (SpanControllerOptions::commit_time has the derivation).
  bool Collides(int k, const Eigen::Vector2d& x, double radius,
                const ChanceThreshold& threshold) const;
  /// Largest bound over the pedestrians at step k (for tests and plots).
  double MaxBound(int k, const Eigen::Vector2d& x, double radius) const;
  /// Union bound on colliding with any pedestrian at step k: sum_n sum_r alpha_r bound_{n,r}
  /// (P(any) <= sum_n P_n; may exceed 1). Components farther than radius + 6 sigma (a term below
  /// 1e-9) and non-finite ones are skipped.
  double UnionBound(int k, const Eigen::Vector2d& x, double radius) const;

  const Eigen::Vector2d& Mean(int n, int k, int r) const { return mean_[Index(n, k, r)]; }
  const Eigen::Matrix2d& Cov(int n, int k, int r) const { return cov_[Index(n, k, r)]; }
  double Alpha(int n, int r) const { return alpha_[static_cast<std::size_t>(n * r_ + r)]; }

 private:
  std::size_t Index(int n, int k, int r) const {
    return (static_cast<std::size_t>(n) * steps_ + static_cast<std::size_t>(k - 1)) * r_ + r;
  }
  int n_ = 0, steps_ = 0, r_ = 1, commit_steps_ = 0;
  std::vector<double> alpha_;          ///< [N * R]
  std::vector<Eigen::Vector2d> mean_;  ///< [N * K * R]
  std::vector<Eigen::Matrix2d> cov_;   ///< [N * K * R]
  std::vector<double> reach_;          ///< [N * K * R]: sqrt of the largest eigenvalue of cov
};

}  // namespace foresight::nav
