#pragma once
/// A synthetic stand-in for Occ-Traj120 (thesis ch 6) so that a fresh clone runs without
/// ../shared: square maps of rooms off a corridor, with trajectories planned between an entry
/// region and several exits, in the Occ-Traj120 conventions (core/binary_grid.h, cell units,
/// waypoints about 1.5 cells apart, every waypoint free).
///
/// Each map: a border wall; a corridor (straight or L-shaped, 3-5 cells wide) at a random place;
/// 2-5 rectangular rooms on either side joined to it by doors 2-3 cells wide. Trajectories of one
/// map start in one entry region (a door or a corridor end, start spread ~1.5 cells) and go to one
/// of 2-4 exits (other doors / ends) chosen with map-specific probabilities. Paths come from an
/// 8-connected A* on the grid whose cost favours clearance from walls (a distance transform), then
/// are shortcut-smoothed (only where the straight segment stays free), resampled at the step
/// length and jittered slightly (every jittered waypoint stays free). Similar layouts give similar
/// motion, which is what OTNet learns to transfer.

#include <cstdint>
#include <vector>

#include "datasets/occ_traj.h"

namespace foresight::otnet {

struct SyntheticRoomsOptions {
  int size = 40;                  ///< map is size x size cells (>= 20)
  int maps = 60;                  ///< number of maps (>= 1)
  int trajectories_per_map = 50;  ///< (>= 1)
  double step = 1.5;              ///< waypoint spacing (cells, > 0)
  double start_spread = 1.5;      ///< std of the start around its entry point (cells, >= 0)
  double jitter = 0.3;            ///< std of the waypoint jitter (cells, >= 0)
  /// 0: every map has its own layout. n > 0: map k belongs to layout family k % n (the same rooms,
  /// corridor, exits and exit weights, as Occ-Traj120's near-duplicate layouts) with 1-3 pillars
  /// (2 x 2 blocks) of its own, so maps of a family are similar, not equal.
  int layouts = 0;
  std::uint64_t seed = 0;
};

/// Generates the maps with ids "synthetic_<k>"; deterministic for given options. Error on an
/// option out of range (naming it).
std::vector<MapTrajectories> GenerateRoomsAndCorridors(const SyntheticRoomsOptions& options);

/// The planner used by the generator, exposed for tests: the 8-connected A* path of cell centres
/// (x = c + 0.5, y = r + 0.5) from cell `from` to cell `to` ((row, col)), cost per move = length x
/// (1 + clearance_weight / (1 + distance to the nearest occupied cell)); never cuts an occupied
/// corner. Empty when unreachable; Error when an end is occupied or outside.
Eigen::MatrixX2d PlanGridPath(const BinaryGrid& map, Eigen::Vector2i from, Eigen::Vector2i to,
                              double clearance_weight);

}  // namespace foresight::otnet
