#pragma once
/// OTNet's evaluation (thesis ch 6, "Dataset and Metrics"), torch-free: the exported engine and
/// two baselines on the held-out maps, with one code path for all three:
///   - OTNet: generate eval.generated collision-free trajectories per map from the predicted
///     mixture (rejection counted), ANLL from the mixture's exact per-time marginals;
///   - k-NN (k = 1, thesis): the trajectories of the nearest training map by delta_H, transferred
///     as they are; ANLL from a Gaussian per tau fitted to them;
///   - mean trajectory: the mean over all training trajectories at each tau, whatever the map;
///     ANLL from a Gaussian per tau fitted to all training trajectories.
/// Scores per map (MTD = mean over generated of the nearest ground truth, Hausdorff and Frechet;
/// coverage = mean over ground truth of the nearest generated; ANLL), then the mean over maps.
/// With eval.conditioned, OTNet is also conditioned on each map's mean ground-truth start (kAll)
/// and k-NN's trajectories are translated to start there (the simplest conditioned baseline).

#include <string>
#include <utility>
#include <vector>

#include "inference/otnet/otnet_model.h"
#include "training/otnet/config.h"
#include "training/otnet/data.h"

namespace foresight::otnet {

using Scores = std::vector<std::pair<std::string, double>>;

/// MTD of one generated trajectory: min over `truth` of the distance, exactly, skipping candidates
/// whose cheap lower bound (Frechet: the endpoint distances; Hausdorff: the endpoints' distances
/// to the other set) cannot beat the best so far. Equals the brute-force minimum (tested).
double MinimumDistance(const Eigen::MatrixX2d& generated,
                       const std::vector<Eigen::MatrixX2d>& truth, TrajectoryDistance d);

/// The centre of the free cell nearest to p (p itself when its cell is free). Error when the map
/// has no free cell.
Eigen::Vector2d NearestFreeCentre(const BinaryGrid& g, const Eigen::Vector2d& p);

/// Scores of OTNet and the baselines on `split` (keys prefixed with `prefix`). `train` gives the
/// k-NN database and the mean trajectory. When plot_png is not empty, draws the first maps.
Scores ScoreSplit(const ExperimentConfig& c, const OtnetModel& model, const OtnetSplit& train,
                  const OtnetSplit& split, const std::string& prefix, const std::string& plot_png);

/// Scores the validation and the test maps; transfer (when configured); returns eval.json's text.
std::string EvaluateOtnet(const ExperimentConfig& c, const OtnetData& d,
                          const std::string& artifact, const std::string& plot_dir);

}  // namespace foresight::otnet
