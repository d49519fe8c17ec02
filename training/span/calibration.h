#pragma once
/// Post-hoc calibration of a SPAN predictor's covariances (an extension of the thesis, issue 12):
/// one scale c on every predicted covariance, c (phi' U phi) V, chosen to minimise the
/// negative log-likelihood of the true positions on validation windows. Scaling V keeps the
/// output a mixture of matrix normals; the mean and the mixture weights do not change.
/// Torch-free.

#include <vector>

#include "datasets/windows.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::span {

/// What the NLL of one true position needs from one component r at one horizon: the log weight
/// log alpha_r - 1/2 log det Sigma_r and the squared Mahalanobis distance d2_r under Sigma_r.
/// Under the scale c: log N = log_weight - log(2 pi) - log c - d2 / (2 c).
struct ScaleTerm {
  double log_weight = 0, d2 = 0;
};
/// Terms of one (window, horizon) point: one per component.
using PointTerms = std::vector<ScaleTerm>;

/// Terms of every predicted point (all horizons) of `windows` under `model` (its own c ignored:
/// the terms are those of c = 1 relative to the model's covariances).
std::vector<PointTerms> CovarianceScaleTerms(const Predictor& model, const WindowSet& windows);

/// Mean negative log-likelihood per point of `terms` when every covariance is scaled by c.
double ScaledNll(const std::vector<PointTerms>& terms, double c);

/// argmin over c in [1e-3, 1e3] of ScaledNll: a grid in log c, then golden-section refinement
/// around the best grid point (for one component the NLL is convex in log c and the minimiser is
/// the closed form mean(d2) / 2). Error when `terms` is empty.
double FitCovarianceScale(const std::vector<PointTerms>& terms);

}  // namespace foresight::span
