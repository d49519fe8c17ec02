#pragma once
/// Synthetic pedestrian tracks: several flows crossing a square area, with turning and varying
/// speeds, sampled at a fixed step with position noise. Used by configs/quickstart.yaml so the
/// main job runs on a fresh machine without ../shared.

#include <cstdint>

#include "core/config.h"
#include "datasets/tracks.h"

namespace foresight {

struct SyntheticPedestrianConfig {
  int num_tracks = 600;
  std::int64_t seed = 1;
  int num_flows = 4;
  double area_size = 20.0;        ///< side of the square area (m)
  double speed_min = 0.6;         ///< m/s
  double speed_max = 1.6;         ///< m/s
  double speed_noise = 0.05;      ///< std of the per-step speed random walk (m/s)
  double turn_rate_max = 0.35;    ///< |omega| of a turning segment (rad/s)
  double turn_probability = 0.5;  ///< chance that a track contains a turning segment
  double position_noise = 0.02;   ///< std of the measurement noise (m)
  double seconds_per_step = 0.4;
  int min_steps = 24;
  int max_steps = 50;

  template <class A>
  void Serialize(A* a) {
    a->Visit("num_tracks", &num_tracks, config::Range::AtLeast(1), "number of tracks to generate");
    a->Visit("seed", &seed, config::Range::Any(), "generator seed");
    a->Visit("num_flows", &num_flows, config::Range::AtLeast(1), "number of main flow directions");
    a->Visit("area_size", &area_size, config::Range::Positive(), "side of the square area (m)");
    a->Visit("speed_min", &speed_min, config::Range::Positive(), "minimum preferred speed (m/s)");
    a->Visit("speed_max", &speed_max, config::Range::Positive(), "maximum preferred speed (m/s)");
    a->Visit("speed_noise", &speed_noise, config::Range::NonNegative(),
             "std of the per-step speed random walk (m/s)");
    a->Visit("turn_rate_max", &turn_rate_max, config::Range::NonNegative(),
             "largest turn rate of a turning segment (rad/s)");
    a->Visit("turn_probability", &turn_probability, config::Range::Closed(0, 1),
             "probability that a track turns once");
    a->Visit("position_noise", &position_noise, config::Range::NonNegative(),
             "std of the position measurement noise (m)");
    a->Visit("seconds_per_step", &seconds_per_step, config::Range::Positive(), "sampling step (s)");
    a->Visit("min_steps", &min_steps, config::Range::AtLeast(2), "shortest track (points)");
    a->Visit("max_steps", &max_steps, config::Range::AtLeast(2), "longest track (points)");
  }
};

/// Deterministic in the config (seed included).
TrackSet GenerateSyntheticPedestrians(const SyntheticPedestrianConfig& config);

}  // namespace foresight
