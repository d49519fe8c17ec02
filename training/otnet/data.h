#pragma once
/// OTNet's data preparation (thesis ch 6), torch-free: read (or generate) the maps and their
/// trajectories, split them by map, fit every trajectory's RBF weights, choose the database of
/// representative maps and encode every map by its similarities to it.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/occ_traj.h"
#include "inference/otnet/map_encoding.h"
#include "inference/otnet/trajectory_basis.h"
#include "training/otnet/config.h"

namespace foresight::otnet {

/// Every trajectory is resampled to this many points at uniform normalised time (linear
/// interpolation, as the authors' script) before its ridge fit: with fewer waypoints than basis
/// functions the fit would sag between the waypoints.
inline constexpr int kFitPoints = 100;

struct OtnetSplit {
  std::vector<MapTrajectories> maps;
  ReadReport report;  ///< what the reader kept and dropped (zeros for synthetic data)
  int trajectories() const;
};

struct OtnetData {
  OtnetSplit train, val, test;
};

/// Reads Occ-Traj120 (or generates the synthetic maps) and splits by map (SplitMaps with the
/// config's seed; synthetic maps by layout family). Logs the split sizes and every dropped
/// trajectory count. Error when a split has no trajectories.
OtnetData LoadOtnetData(const ExperimentConfig& c);

TrajectoryBasis MakeBasis(const ExperimentConfig& c);

/// Indices into `maps` of the representative database: all (database_size 0 or >= maps), else a
/// greedy farthest-point (k-centre) subset under delta_H, starting from map 0.
std::vector<int> ChooseDatabase(const std::vector<MapTrajectories>& maps, int database_size);
MapEncoder MakeEncoder(const ExperimentConfig& c, const std::vector<MapTrajectories>& train);

/// A split as the network sees it: phi per map, and per trajectory its map's row and its weights.
struct EncodedSplit {
  Eigen::MatrixXd phi;                  ///< [maps x D]
  std::vector<std::int64_t> map_index;  ///< [N]
  Eigen::MatrixXd w;                    ///< [N x 2M]
};
EncodedSplit EncodeSplit(const MapEncoder& encoder, const TrajectoryBasis& basis,
                         const OtnetSplit& split);

/// Root-mean-square distance (cells) between the resampled trajectories of `split` and their basis
/// reconstruction at the kFitPoints uniform taus: how much the representation loses.
double ReconstructionRmse(const TrajectoryBasis& basis, const OtnetSplit& split);

}  // namespace foresight::otnet
