#pragma once
/// Scenes with maps for structurally constrained motion prediction (thesis ch 7: observe 10 steps,
/// predict T): an obstacle raster and the tracks recorded in it, from four sources
///   synthetic  rooms with a central block and pillars, tracks walking around them (no files);
///   occ_traj   Occ-Traj120 maps and trajectories (the thesis's "simulated"; cell units, 1 step per
///              waypoint; ../shared/data/occ_traj120/README.md);
///   thor       THOR runs thor1 / thor3 with their obstacle maps (the thesis's "indoors", metres,
///              resampled to `step`; ../shared/data/thor/README.md);
///   eth        ETH seq_eth / seq_hotel with map.png and H.txt (standing in for the non-public
///              traffic set; ../shared/data/eth_ucy/README.md, section eth_original).
/// Every returned track lies inside its scene's raster extent; samples on occupied cells are kept
/// and counted (MapTracksReport), since a misregistered map or homography shows up that way.

#include <cstdint>
#include <string>
#include <vector>

#include "core/binary_grid.h"
#include "core/config.h"
#include "datasets/crowd_scenario.h"
#include "datasets/tracks.h"

namespace foresight {

/// One scene: an obstacle raster and the tracks recorded in it (same frame, metres or cell units).
struct MapScene {
  std::string name;        ///< "thor1", "seq_eth", "occtraj_<id>", "synthetic_3"
  OccupancyRaster raster;  ///< ground-truth obstacles; outside the extent counts as occupied
  TrackSet tracks;         ///< uniformly sampled at tracks.seconds_per_step
};

/// What loading dropped, per reason, summed over scenes (each reason is also logged once per scene
/// with log::Info/Warn, naming the scene).
struct MapTracksReport {
  int scenes = 0;         ///< scenes returned (with at least one track)
  int tracks_read = 0;    ///< tracks offered to the checks (after resampling for thor/eth)
  int tracks_kept = 0;    ///< tracks returned
  int too_short = 0;      ///< fewer than min_points samples (skipped)
  int outside_frame = 0;  ///< a sample outside the raster's extent (map frame does not cover it)
  int points_in_obstacles = 0;  ///< samples on occupied cells (kept; counted: e.g. a homography or
                                ///< map misregistration puts tracks into obstacles)
  int tracks_in_obstacles = 0;  ///< kept tracks with at least one such sample
  int points_kept = 0;          ///< samples of the kept tracks (denominator of the share above)

  void Add(const MapTracksReport& o);  ///< sums every count
  /// One line: "2 scenes, 120/140 tracks kept (too short 15, outside frame 5), 12 of 3400
  /// samples (0.35 %) in 3 tracks on obstacles".
  std::string BriefReport() const;
};

struct MapTracksConfig {
  std::string source = "synthetic";  ///< synthetic | occ_traj | thor | eth
  std::string root;                  ///< data root override (empty: datasets/data_root.h rules)
  std::vector<std::string> scenes;   ///< thor: {"thor1","thor3"}; eth: {"seq_eth","seq_hotel"};
                                     ///< occ_traj: map ids (empty: the first `max_maps` listed);
                                     ///< thor/eth: empty = both
  int max_maps = 20;                 ///< occ_traj / synthetic: number of maps
  double resolution = 0.1;    ///< raster cell (m; occ_traj: cell units, 1/resolution an integer:
                              ///< 1.0 is the map's own grid, 0.1 splits each cell 10 x 10, exactly)
  double step = 0.4;          ///< track sampling step (s) after resampling (thor/eth; 0.4)
  double max_gap = 1.0;       ///< thor/eth: a gap longer than this splits a track (s)
  int synthetic_tracks = 40;  ///< synthetic: tracks per map
  std::int64_t synthetic_seed = 1;  ///< synthetic generator seed

  template <class A>
  void Serialize(A* a) {
    a->Visit("source", &source, config::Range::Any(),
             "scenes with maps: synthetic | occ_traj | thor | eth");
    a->Visit("root", &root, config::Range::Any(),
             "data root; empty = $FORESIGHT_DATA or ../shared/data");
    a->Visit("scenes", &scenes, config::Range::Any(),
             "thor: thor1, thor3; eth: seq_eth, seq_hotel (empty = both); occ_traj: map ids "
             "(empty = the first max_maps of train_maps.txt); synthetic: unused");
    a->Visit("max_maps", &max_maps, config::Range::AtLeast(1),
             "occ_traj / synthetic: number of maps");
    a->Visit("resolution", &resolution, config::Range::Open(0, 10),
             "obstacle raster cell (m; occ_traj: cells, 1/resolution an integer)");
    a->Visit("step", &step, config::Range::Open(0, 10),
             "thor / eth: track sampling step after resampling (s)");
    a->Visit("max_gap", &max_gap, config::Range::Positive(),
             "thor / eth: a longer gap between samples splits a track (s)");
    a->Visit("synthetic_tracks", &synthetic_tracks, config::Range::AtLeast(1),
             "synthetic: tracks per map");
    a->Visit("synthetic_seed", &synthetic_seed, config::Range::NonNegative(),
             "synthetic: generator seed");
  }
  /// Throws foresight::Error naming `source` (file) and the key (data.source, data.scenes,
  /// data.resolution, data.max_gap): an unknown source, an unknown or repeated scene name, an
  /// occ_traj resolution whose inverse is not an integer, max_gap below step.
  void Validate(const std::string& source) const;
};

/// Loads every scene of `config`; tracks with fewer than `min_points` samples are dropped and
/// counted (callers pass observed + predicted). Missing files are Errors naming the path and the
/// config key (data.root / data.scenes). A scene whose raster does not cover a track: the track is
/// dropped and counted (outside_frame). Never returns a scene with zero tracks silently: such
/// scenes are dropped with a log line; zero scenes overall is an Error. `report` may be null; its
/// counts are added to.
///   thor: ReadThorTracks + ResampleTracks(step, max_gap); ThorMapRaster on the tracks' bounding
///         box + 1 m, clipped to the map image (x in [-11, 12], y in [-10, 13.5]).
///   eth:  ReadEthObsmat + ResampleTracks(step, max_gap); EthMapRaster with the H.txt beside
///         obsmat.txt on the tracks' bounding box + 2 m.
///   occ_traj: one waypoint per time unit (seconds_per_step 1), cell units; OccTrajRaster.
///   synthetic: GenerateMapScenes(max_maps, synthetic_tracks, min_points, synthetic_seed).
std::vector<MapScene> LoadMapScenes(const MapTracksConfig& config, int min_points,
                                    MapTracksReport* report);

/// Synthetic scenes without data files (quickstart, tests), in metres at 0.1 m cells, tracks at
/// 0.4 s: rooms of about 16 m x 12 m with a 0.3 m border wall, a central block and two pillars.
/// Tracks go from one side to the other (3/4 across, 1/4 to the top or bottom of the far half;
/// half of them start and end level with the block) at 1.0-1.4 m/s. When the block is in the way
/// a track heads for it along the straight line, swerves around it late and rejoins the line
/// (corner-cut polyline), so a constant-velocity extrapolation of the approach hits the block.
/// A smooth lateral wander (<= 0.15 m) and 1 cm noise are added. Every sample is on a free cell
/// with free cells 0.2 m around it; every track has >= min_points samples (the room widens with
/// min_points). Scene k is named "synthetic_<k>". Deterministic in the seed (own uniform and
/// normal draws, not std distributions). About 25 ms for 20 maps x 40 tracks.
std::vector<MapScene> GenerateMapScenes(int maps, int tracks_per_map, int min_points,
                                        std::uint64_t seed);

/// Splits the scenes' tracks into train/val/test. by_scene=true: whole scenes (map-level split,
/// occ_traj/synthetic) with otnet::SplitMaps on the scene names (every part non-empty, else an
/// Error). by_scene=false: tracks within each scene (thor/eth, only 2 scenes) with SplitTracks
/// (seed mixed with the scene index); each part keeps a scene only when it got tracks of it, with
/// the scene's raster. Deterministic in seed.
struct MapTracksSplit {
  std::vector<MapScene> train, val, test;
};
MapTracksSplit SplitMapScenes(const std::vector<MapScene>& scenes, bool by_scene,
                              double val_fraction, double test_fraction, std::uint64_t seed);

/// The checks LoadMapScenes applies to each scene, exposed for tests and for callers that build
/// scenes themselves: drops tracks with fewer than `min_points` samples (too_short), then tracks
/// with a sample outside the raster's cells or not finite (outside_frame), and counts the samples
/// of kept tracks on occupied cells. Adds to `report` (may be null; `scenes` is not touched) and
/// logs each non-zero reason once, naming the scene.
void CheckSceneTracks(MapScene* scene, int min_points, MapTracksReport* report);

/// True when (x, y) falls in one of the raster's cells (OccupancyRaster::Occupied's indexing).
bool InsideRaster(const OccupancyRaster& raster, double x, double y);

/// An Occ-Traj120 BinaryGrid (cell (r, c) covers x in [c, c+1), y in [r, r+1)) as an
/// OccupancyRaster (row 0 = y_max) with cells of 1/subdivisions grid cells: raster row i holds grid
/// row height - 1 - floor(i / subdivisions). The extent is [0, width] x [0, height] shifted by
/// -1e-9 so that a coordinate on a cell boundary (y = 5.00) falls in grid row floor(y), as
/// BinaryGrid::OccupiedAt does (OccupancyRaster rounds the other way in y).
OccupancyRaster OccTrajRaster(const BinaryGrid& grid, int subdivisions = 1);

}  // namespace foresight
