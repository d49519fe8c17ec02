#pragma once
/// Training pairs (observed past, future RBF weights W) in the ego frame (core/ego_frame.h).

#include <Eigen/Core>

#include "core/rbf.h"
#include "datasets/windows.h"
#include "models/span/span_config.h"

namespace foresight::span {

/// Basis over the prediction horizon [0, f dt] (s), t = 0 at the last observed point; centres on
/// [-margin, f dt + margin].
TimeBasis MakeFutureBasis(const TrajectoryBasisConfig& config, int predicted,
                          double seconds_per_step);

struct Samples {
  Eigen::MatrixXd inputs;   ///< [N x 2p] past points in the ego frame (x_1, y_1, ...)
  Eigen::MatrixXd targets;  ///< [N x 2m] W (m x 2) row-major, ego frame (m)
};

/// Ego-frame inputs and ridge-fitted future weights (thesis eq. lsuqares) for every window.
/// With `residual_to_constant_velocity`, the fitted futures are y(t) - v t (v: last step's
/// velocity).
Samples MakeSamples(const WindowSet& windows, const TimeBasis& basis,
                    const TrajectoryBasisConfig& config, bool rotate,
                    bool residual_to_constant_velocity = false);

/// The samples of `samples` followed by their copies at each of `augment.speed_scales` and, with
/// `augment.mirror`, all of those mirrored (ego y -> -y); see AugmentConfig. Scales must be
/// positive and differ from 1 (a copy at 1 would only repeat the data): an Error names the value.
Samples Augment(const Samples& samples, const AugmentConfig& augment);

}  // namespace foresight::span
