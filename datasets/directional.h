#pragma once
/// Motion-direction samples (x, y, t, theta) for spatiotemporal directional maps (thesis ch 4).
/// Positions in metres in a right-handed frame, t in seconds, theta in [-pi, pi) measured
/// counter-clockwise from +x. Readers turn tracks into samples: the heading of consecutive points,
/// dropping standing or noisy points (counts are reported in the stats and logged).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace foresight {

struct DirectionalSamples {
  Eigen::VectorXd x, y, t, theta;  ///< [n] each
  /// [n] or empty: id of the path (track) each sample came from, for path-grouped folds
  /// (GroupedKFoldTestIndices). Ids are unique per path within one reader call; not necessarily
  /// contiguous. Empty when unknown.
  std::vector<std::int64_t> path;
  Eigen::Index size() const { return x.size(); }
  /// Rows `index` (for splits); carries `path` when it is set.
  DirectionalSamples Select(const std::vector<Eigen::Index>& index) const;
  /// Throws an Error naming `where` if empty, any value is non-finite, theta is outside [-pi,
  /// pi) or `path` is neither empty nor of size n.
  void Validate(const std::string& where) const;
};

/// What a reader kept and dropped.
struct DirectionalReadStats {
  std::int64_t points = 0, tracks = 0, kept = 0;
  std::int64_t dropped_standing = 0, dropped_jump = 0, dropped_gap = 0, dropped_short_track = 0;
  /// First point of each kept track: it has no previous point, hence no heading. Every point is
  /// counted once: points == kept + first_points + dropped_standing + dropped_jump + dropped_gap +
  /// dropped_short_track.
  std::int64_t first_points = 0;
  std::int64_t dropped() const {
    return dropped_standing + dropped_jump + dropped_gap + dropped_short_track;
  }
};

struct HeadingFilter {
  double min_speed = 0.1;    ///< m/s; slower steps are "standing"
  double max_speed = 4.0;    ///< m/s; faster steps are tracking jumps
  double max_gap = 2.0;      ///< s; longer gaps between consecutive points break the track
  int min_track_points = 5;  ///< tracks with fewer points (false detections) are dropped whole
};

/// Time of the directional_grid_maps_sim rows, which have none: row index within its path times
/// this (s). An assumption (mouse-drawn way-points ~0.1-0.3 m apart, i.e. walking pace).
inline constexpr double kDirectionalGridSecondsPerRow = 0.1;
/// directional_grid_maps_sim: a step longer than this (m) is a jump (two drawn paths under one id).
inline constexpr double kDirectionalGridMaxStep = 5.0;
/// Edinburgh Informatics Forum: ground size of one pixel (README: 24.7 mm), image height (pixels,
/// y grows down) and the nominal frame rate (README: ~9 frames/s; frames carry no time stamp).
inline constexpr double kEdinburghMetresPerPixel = 0.0247;
inline constexpr double kEdinburghImageHeight = 480;
inline constexpr double kEdinburghFramesPerSecond = 9.0;

/// ../shared/data/directional_grid_maps_sim/{unimodal_sim1,multimodal_sim2}.csv (P1 / P2). See its
/// README for the heading convention and the missing timestamps (t is then the sample index
/// scaled by `seconds_per_row`; documented in docs/dataset_schema.md).
/// Heading = orientation_raw + pi/2 (README convention), checked against the step from the
/// previous row of the path (an Error naming file:line when they disagree by 1e-4 rad or more).
/// t = (row index within its path) * kDirectionalGridSecondsPerRow. The first row of a path has no
/// heading (first_points); a repeated way-point is dropped_standing; a step longer than
/// kDirectionalGridMaxStep is dropped_jump. Positions are kept as they are (m, right-handed).
/// `path`: 0, 1, 2, ... in file order, one per drawn path (file path_id); a jump splits the drawn
/// path, and the rows after it get the next id (the two pieces are different walks).
DirectionalSamples ReadDirectionalGridCsv(const std::string& path,
                                          DirectionalReadStats* stats = nullptr);

/// ../shared/data/edinburgh_forum/tracks.*.txt: pixels (y down) -> metres (right-handed),
/// irregular frame times -> seconds since the first point of the file.
///   x = x_px * kEdinburghMetresPerPixel,  y = (kEdinburghImageHeight - 1 - y_px) *
///   kEdinburghMetresPerPixel, t = (frame - earliest frame of the file) /
///   kEdinburghFramesPerSecond,
/// theta of point i = atan2(y_i - y_{i-1}, x_i - x_{i-1}) (metres), kept at point i. Per step:
/// dt > max_gap -> dropped_gap (the track restarts there); two points in one frame or speed >
/// max_speed -> dropped_jump; speed < min_speed or no motion -> dropped_standing. Tracks with fewer
/// than min_track_points points -> dropped_short_track. Malformed lines, non-finite or
/// non-integer values, frames going back and a TRACK that disagrees with its Properties line
/// (n_points, first and last frame) are Errors naming file:line.
/// `path`: 0, 1, 2, ... in file order, one per kept TRACK, and a new id where a gap restarts it.
DirectionalSamples ReadEdinburghTracks(const std::string& path, const HeadingFilter& filter,
                                       DirectionalReadStats* stats = nullptr);

/// Synthetic time-varying flows: "pedestrian crossing 3" of the thesis. Pedestrians cross a
/// square; the dominant direction of the crossing flips between the two halves of [0, duration].
/// Track k starts at t0 ~ U[0, duration - size/speed] on the left (x = 0) or right (x = size)
/// edge at y0 ~ U[0.1, 0.9] size and steers at y1 ~ U[0.1, 0.9] size on the far edge with
/// heading = atan2(goal - p) + N(0, heading_noise^2) per step of speed * sample_period. While the
/// track's middle time is in the first half it goes +x with probability dominant_fraction, else
/// -x; in the second half the other way round. Samples (position after each step, its time and
/// heading) stop at the square's border. Same config, same samples (own draws on mt19937_64).
/// `path` = the track index k (tracks that leave no sample leave a gap in the ids).
struct CrossingFlowConfig {
  int num_tracks = 400;
  double duration = 100.0;          ///< s (time axis of the map)
  double size = 10.0;               ///< m (square side)
  double speed = 1.2;               ///< m/s
  double heading_noise = 0.15;      ///< rad (per step)
  double sample_period = 0.5;       ///< s between samples along a track
  double dominant_fraction = 0.95;  ///< share of the tracks of each half that go the dominant way
  std::uint64_t seed = 0;
};
DirectionalSamples GenerateCrossingFlow(const CrossingFlowConfig& config);

/// K folds of a shuffled index (seeded): fold k's test rows (sorted); the rest train. Every row
/// is in exactly one test fold; fold sizes differ by at most one. K >= 2 and n >= K, else an Error.
/// The thesis's point-wise protocol: neighbouring way-points of one path land in different folds.
std::vector<std::vector<Eigen::Index>> KFoldTestIndices(Eigen::Index n, int k, std::uint64_t seed);

/// K folds that keep groups whole (path-grouped folds): `groups` [n] holds the group (path) id of
/// each row; every row of a group is in the same test fold. The distinct ids are sorted, shuffled
/// with `seed` (Fisher-Yates on mt19937_64), then stably sorted by size, largest first, and each
/// group goes to the fold with the fewest rows so far (the lowest fold index on ties): fold sizes
/// are as balanced as the groups allow (greedy longest-processing-time; max - min <= the largest
/// group). Returns each fold's test rows, sorted. Same groups and seed, same folds. K >= 2 and at
/// least K distinct groups, else an Error naming k and the number of groups.
std::vector<std::vector<Eigen::Index>> GroupedKFoldTestIndices(
    const std::vector<std::int64_t>& groups, int k, std::uint64_t seed);

}  // namespace foresight
