#pragma once
/// Metrics of structurally constrained prediction (thesis ch 7, "Datasets and Metrics"), shared by
/// the prior, the optimised distribution and the baselines (constant velocity, naive network, KTM):
///   ADE / FDE  of the mean of the component nearest to the truth (the thesis' definition; nearest
///              by ADE), and of the mixture mean;
///   AL         the average likelihood: the mixture density p(x_t) of the true position, averaged
///              over the f predicted steps (a density in 1/m^2, not a log, as the thesis);
///   ANLL       the mean of -log p(x_t) over the steps (reported too: AL is dominated by easy
///   steps).
/// The constraint-violation share (C.V.P) is a count over tracks of DistributionProjector::Cost.

#include <Eigen/Core>
#include <vector>

#include "inference/prediction/span_predictor.h"

namespace foresight::constrained {

/// Metrics of one prediction against the ground-truth future [f x 2] at times dt, 2dt, ..., f dt.
struct PredictionScores {
  double ade_nearest = 0, fde_nearest = 0;  ///< of the mean of the component nearest to the truth
                                            ///< (nearest by ADE; thesis' definition) (m)
  double ade_mixture = 0, fde_mixture = 0;  ///< of the mixture mean (m)
  double al = 0;  ///< average likelihood: mean over the f steps of the mixture density p(x_t)
                  ///< (1/m^2), as the thesis (a density, not a log)
  double anll =
      0;  ///< mean over steps of -log p(x_t) (reported too; AL is dominated by easy steps)
  int nearest = 0;  ///< index of the nearest component (0 for point predictions)
};

/// @param d the predicted distribution (world frame, t in s after the last observation).
/// @param truth [f x 2] true positions (world, m) at dt, 2 dt, ..., f dt. @param dt step (s).
/// Error when truth is empty or not finite, dt is not positive, or d has no component.
PredictionScores ScorePrediction(const TrajectoryDistribution& d,
                                 const Eigen::Ref<const Eigen::MatrixX2d>& truth, double dt);

/// Point predictions (constant velocity, naive network) [f x 2] against truth [f x 2]: ADE/FDE
/// only (nearest = mixture; al/anll NaN). Error when the row counts differ or are 0.
PredictionScores ScorePoints(const Eigen::Ref<const Eigen::MatrixX2d>& predicted,
                             const Eigen::Ref<const Eigen::MatrixX2d>& truth);

/// Constant velocity from the last two observed points of `past` [p x 2] (p >= 2, one point per
/// step): f >= 1 future points [f x 2], row i = last + (i + 1) (last - previous).
Eigen::MatrixX2d ConstantVelocity(const Eigen::Ref<const Eigen::MatrixX2d>& past, int f);

/// Percentile q in [0, 100] of a sample with linear interpolation between order statistics
/// (numpy's default: position q/100 (n - 1)); NaN for an empty sample. Error for q outside
/// [0, 100] or a NaN in the sample.
double Percentile(std::vector<double> v, double q);

}  // namespace foresight::constrained
