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
  std::vector<MapTrajectories> maps;  ///< as read, then the symmetric copies (data.augment)
  ReadReport report;  ///< what the reader kept and dropped (zeros for synthetic data)
  int copies = 0;     ///< the last `copies` maps are symmetric copies of the ones before
  int trajectories() const;
  /// The maps as read or generated (without the symmetric copies).
  std::vector<MapTrajectories> OriginalMaps() const;
};

struct OtnetData {
  OtnetSplit train, val, test;
};

/// Reads Occ-Traj120 (or generates the synthetic maps) and splits by map (SplitMaps with the
/// config's seed; synthetic maps by layout family). Logs the split sizes and every dropped
/// trajectory count. Error when a split has no trajectories.
OtnetData LoadOtnetData(const ExperimentConfig& c);

/// Symmetry `s` in [0, 8) of a square map and its trajectories: bit 2 swaps x and y (applied
/// first), bit 0 reflects x (x -> W - x, cell c -> W - 1 - c), bit 1 reflects y. 0 is the identity.
/// A waypoint on a cell boundary (an integer coordinate) lands in the neighbouring cell after a
/// reflection; a trajectory that then has a waypoint in an occupied cell is dropped and counted
/// in `*dropped`. Error for a map that is not square.
MapTrajectories TransformMap(const MapTrajectories& m, int s, int* dropped);

/// Appends the 7 non-identity symmetries of every map of `split` (ids "<id>@s<k>") and sets
/// `copies`; logs the trajectories dropped by TransformMap.
void AugmentDihedral(OtnetSplit* split);

TrajectoryBasis MakeBasis(const ExperimentConfig& c);

/// Indices into `maps` of the representative database: all (database_size 0 or >= maps), else a
/// greedy farthest-point (k-centre) subset under delta_H, starting from map 0.
std::vector<int> ChooseDatabase(const std::vector<MapTrajectories>& maps, int database_size);
/// The database is chosen among the training maps as read (never their symmetric copies).
MapEncoder MakeEncoder(const ExperimentConfig& c, const OtnetSplit& train);

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
