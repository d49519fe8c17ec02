#pragma once
/// Agent tracks: the common in-memory form of every pedestrian dataset.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace foresight {

/// One agent's uninterrupted track, sampled at a fixed step.
struct Track {
  std::int64_t agent_id = 0;
  std::vector<double> time;                            ///< [n] seconds, increasing
  Eigen::Matrix<double, Eigen::Dynamic, 2> positions;  ///< [n x 2] metres, world frame
  int size() const { return static_cast<int>(time.size()); }
};

struct TrackSet {
  std::string source;             ///< file or generator the tracks came from
  double seconds_per_step = 0.4;  ///< sampling step (s)
  std::vector<Track> tracks;
  std::size_t NumPoints() const;
};

}  // namespace foresight
