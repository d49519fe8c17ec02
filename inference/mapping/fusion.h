#pragma once
/// Decentralised fusion of Fast-BHMs (thesis ch 3, "Merging Bayesian Hilbert Maps"), on maps that
/// share one feature grid.
///
/// Conflation (Hill 2008; thesis eq. Conflate): the product of Gaussian estimates of a weight,
///   1/s2 = sum_i 1/s2_i,   mu = s2 sum_i mu_i / s2_i,
/// over the *informative* estimates only: a local estimate whose variance is not below
/// `variance_threshold` learned (almost) nothing and is filtered out; a weight with no informative
/// estimate keeps the prior.
///
/// Repeated fusion: each robot keeps a copy of the last global map M and trains it further to M u
/// N; its increment (spec/errata.md, ch 3)
///   1/s2_N = 1/s2_MuN - 1/s2_M,   mu_N = s2_N (mu_MuN / s2_MuN - mu_M / s2_M)
/// is what it learned since; where s2_MuN >= s2_M it learned nothing and the increment is left
/// out. The new global map is the conflation of M with all increments (M carries the shared,
/// common information exactly once).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "inference/mapping/hinge_map.h"

namespace foresight::occupancy {

struct FusionOptions {
  double variance_threshold = 1000.0;  ///< local estimates with variance >= this are ignored
};

/// Per-weight Gaussian estimates; variance +inf marks "no information".
struct WeightEstimate {
  Eigen::VectorXd mean, variance;
};

/// The estimate held by a Fast-BHM (its weight means and variances).
WeightEstimate EstimateOf(const HingeMap& map);
/// What `local` learned since it was a copy of `last_global` (increment rule above).
WeightEstimate IncrementOf(const HingeMap& local, const HingeMap& last_global);

/// Conflation of `estimates` (thresholded) and, when given, of `base` (taken whole): the global
/// Fast-BHM on `grid`. Weights without any information keep the prior N(prior_mean,
/// prior_variance).
HingeMap Conflate(const HingeGrid& grid, const std::vector<WeightEstimate>& estimates,
                  const FusionOptions& options, double prior_mean, double prior_variance,
                  const HingeMap* base = nullptr);

/// Fuse once: conflation of independently trained local Fast-BHMs.
/// With `last_global`: one step of repeated fusion (the maps are copies of it trained further).
/// Maps of another kind, feature grid or prior are refused with an Error naming them (`names`).
HingeMap FuseMaps(const std::vector<const HingeMap*>& maps, const std::vector<std::string>& names,
                  const FusionOptions& options, const HingeMap* last_global = nullptr);

}  // namespace foresight::occupancy
