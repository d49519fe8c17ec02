#pragma once
/// Replayed crowds (scenario source `replay`): recorded pedestrians at their true speed, several
/// time windows of one recording overlaid to raise the density. Replayed pedestrians do not react
/// to the robot. Readers of the THOR csv and ETH obsmat formats and of their obstacle images
/// (../shared/data/thor/README.md, ../shared/data/eth_ucy/README.md).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/crowd_scenario.h"
#include "datasets/tracks.h"

namespace foresight {

/// THOR csv `time, person_id, x, y, velocity, motion_angle` (no header): one raw track per tracklet
/// id, samples sorted by time (about 0.4 s apart, not on a common grid). velocity/motion_angle are
/// ignored (coarse bins). Bad rows (field count, non-numbers, NaN/inf, a time twice in a tracklet)
/// are Errors naming file and line.
TrackSet ReadThorTracks(const std::string& path);

/// ETH obsmat `frame ped_id pos_x pos_z pos_y v_x v_z v_y` (y is the 5th column): one raw track per
/// pedestrian. The frame step between annotations is inferred as the most common positive frame
/// difference of one pedestrian and spans `annotation_step` s (0.4 s in seq_eth, frames every 6;
/// seq_hotel, frames every 10), so time = frame * annotation_step / frame_step.
TrackSet ReadEthObsmat(const std::string& path, double annotation_step = 0.4);

/// Each track linearly interpolated to the global grid k * step (s) within its own time span (no
/// extrapolation); a gap longer than `max_gap` s between samples splits the track. Pieces with
/// fewer than two grid points are dropped. Track ids are kept (split pieces share the id).
TrackSet ResampleTracks(const TrackSet& raw, double step, double max_gap);

/// The 3x3 homography of an ETH H.txt (image [row, col, 1] -> world [x, y, 1]).
Eigen::Matrix3d ReadHomography(const std::string& path);

/// THOR map png (0.01 m/px, x in [-11, 12], y in [-10, 13.5], grey > 128 = free) on `extent`
/// [x_min, x_max, y_min, y_max]: a cell is occupied when any dark pixel falls in it or its centre
/// is outside the image.
OccupancyRaster ThorMapRaster(const std::string& image_path, const Eigen::Vector4d& extent,
                              double resolution);

/// ETH map.png (grey > 128 = obstacle) through H ([r, c, 1] ∝ H^-1 [x, y, 1]) on `extent`: a cell
/// is occupied when any obstacle pixel maps into it or its centre maps outside the image.
OccupancyRaster EthMapRaster(const std::string& image_path, const Eigen::Matrix3d& H,
                             const Eigen::Vector4d& extent, double resolution);

/// The replayed crowd of a scenario with source `replay`: its tracks are read, resampled to
/// replay.step, and `overlays` windows of `duration` s, starting `overlay_spacing` s apart, are
/// shifted to start at time 0 and overlaid (ids renumbered 0, 1, ... over windows and tracks). The
/// episode seed draws the first window's start uniformly in [t_first, t_last - duration]; later
/// windows wrap around within that interval. Agents are active while their track covers the current
/// time.
class ReplayCrowd : public Crowd {
 public:
  ReplayCrowd(const CrowdScenarioConfig& scenario, std::uint64_t seed);
  /// From tracks already on the grid `step` (tests; ResampleTracks output).
  ReplayCrowd(const TrackSet& resampled, const ReplayConfig& replay, double radius,
              std::uint64_t seed);

  void Step(double dt, const RobotAgent& robot) override;
  double time() const override { return time_; }
  const std::vector<CrowdAgent>& agents() const override { return agents_; }
  /// Recording time (s) at which each window starts.
  const std::vector<double>& window_starts() const { return window_starts_; }

 private:
  struct Piece {
    double t0 = 0;                                       ///< episode time of the first sample (s)
    Eigen::Matrix<double, Eigen::Dynamic, 2> positions;  ///< on the grid `step_`
  };
  void Init(const TrackSet& resampled, const ReplayConfig& replay, double radius,
            std::uint64_t seed);
  void Update();

  std::vector<Piece> pieces_;
  std::vector<CrowdAgent> agents_;
  std::vector<double> window_starts_;
  double step_ = 0.1, duration_ = 60, time_ = 0;
};

/// Resampled tracks of the scenario's replay source (format, file and root of `replay`).
TrackSet ReadReplayTracks(const ReplayConfig& replay);

/// The obstacle raster of a replay scenario on its extent.
OccupancyRaster ReplayOccupancy(const CrowdScenarioConfig& scenario, double resolution);

}  // namespace foresight
