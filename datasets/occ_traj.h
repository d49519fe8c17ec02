#pragma once
/// Occ-Traj120 (Lai, Zhi, Ramos 2019; ../shared/data/occ_traj120/README.md), the data of OTNet
/// (thesis ch 6): 40 x 40 binary maps printed as numpy arrays and, per map, blocks of
///   traj-<k>:
///   x_1 x_2 ... x_n
///   y_1 y_2 ... y_n
/// in grid-cell units with occupied(x, y) = map[floor(y)][floor(x)] (core/binary_grid.h).
/// Files: <root>/maps/occtraj_<id>_map.txt, <root>/trajs/occtraj_<id>_trajs.txt, and
/// <root>/train_maps.txt listing the ids. Splits are by map, never by trajectory.

#include <cstdint>
#include <string>
#include <vector>

#include "core/binary_grid.h"

namespace foresight::otnet {

/// One map and the trajectories observed in it.
struct MapTrajectories {
  std::string id;  ///< Occ-Traj120 id, or "synthetic_<k>"
  BinaryGrid map;
  std::vector<Eigen::MatrixX2d> trajectories;  ///< waypoints (x, y) per row, cell units
};

/// What to do with a trajectory that has a waypoint outside the map or inside an occupied cell.
enum class BadWaypointPolicy {
  kError,  ///< an Error naming the file, the line and the waypoint
  kDrop,   ///< drop the trajectory and count it (ReadReport)
};

/// Counts of one trajectory file (everything dropped is counted here; the caller logs it).
struct ReadReport {
  int trajectories = 0;           ///< blocks read
  int kept = 0;                   ///< trajectories returned
  int dropped_outside = 0;        ///< dropped: a waypoint outside [0, width) x [0, height)
  int dropped_occupied = 0;       ///< dropped: a waypoint inside an occupied cell
  int dropped_too_short = 0;      ///< dropped: fewer than 2 waypoints
  void Add(const ReadReport& o);  ///< sums the counts (for a whole split)
};

/// Reads a map file. Every row must have the same number of 0/1 entries; with expected_width /
/// expected_height > 0 the size must match. Errors name the file, the line and what was found
/// (a ragged row, a value other than 0/1, a wrong size, no rows).
BinaryGrid ReadOccTrajMap(const std::string& path, int expected_width = 0, int expected_height = 0);

/// Reads a trajectory file for `map`. A block whose x and y lines differ in length, a header that
/// is not `traj-<k>:`, a non-numeric or non-finite value, or a truncated block is an Error naming
/// the file and the line. Bad waypoints follow `policy`; `report` (may be null) gets the counts.
std::vector<Eigen::MatrixX2d> ReadOccTrajTrajectories(const std::string& path,
                                                      const BinaryGrid& map,
                                                      BadWaypointPolicy policy, ReadReport* report);

/// The ids of <root>/train_maps.txt in file order (an Error when missing or empty).
std::vector<std::string> ListOccTrajMaps(const std::string& root);

/// Reads map `id` and its trajectories from `root` (maps must be map_size x map_size).
MapTrajectories LoadOccTrajMap(const std::string& root, const std::string& id, int map_size,
                               BadWaypointPolicy policy, ReadReport* report);

/// A deterministic split of map ids: the ids are sorted, shuffled by std::mt19937_64(seed) and cut
/// into test (round(test_fraction * n)), validation (round(val_fraction * n)) and train (the rest),
/// in that order. Each part is returned sorted. Error when a part would be empty or fractions are
/// outside [0, 1) or sum to >= 1. The same ids and seed give the same split on every machine.
struct MapSplit {
  std::vector<std::string> train, val, test;
};
MapSplit SplitMaps(std::vector<std::string> ids, double val_fraction, double test_fraction,
                   std::uint64_t seed);

}  // namespace foresight::otnet
