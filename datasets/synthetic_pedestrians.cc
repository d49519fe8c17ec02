#include "datasets/synthetic_pedestrians.h"

#include <cmath>
#include <random>

#include "core/error.h"

namespace foresight {

TrackSet GenerateSyntheticPedestrians(const SyntheticPedestrianConfig& c) {
  FS_THROW_UNLESS(c.speed_max >= c.speed_min, "synthetic pedestrians: speed_max ", c.speed_max,
                  " < speed_min ", c.speed_min);
  FS_THROW_UNLESS(c.max_steps >= c.min_steps, "synthetic pedestrians: max_steps ", c.max_steps,
                  " < min_steps ", c.min_steps);
  std::mt19937_64 rng(static_cast<std::uint64_t>(c.seed));
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double dt = c.seconds_per_step;
  const double half = 0.5 * c.area_size;

  TrackSet set;
  set.source = "synthetic_pedestrians";
  set.seconds_per_step = dt;
  for (int k = 0; k < c.num_tracks; ++k) {
    // A flow enters from the boundary heading through the area; lanes spread across it.
    const int flow = static_cast<int>(u01(rng) * c.num_flows) % c.num_flows;
    const double flow_heading = 2.0 * M_PI * flow / c.num_flows + 0.3;
    const double lane = (u01(rng) - 0.5) * 0.6 * c.area_size;
    Eigen::Vector2d dir(std::cos(flow_heading), std::sin(flow_heading));
    Eigen::Vector2d normal(-dir.y(), dir.x());
    Eigen::Vector2d p = -half * dir + lane * normal;
    double heading = flow_heading + 0.15 * n01(rng);
    const double preferred = c.speed_min + (c.speed_max - c.speed_min) * u01(rng);
    double speed = preferred;
    const int steps = c.min_steps + static_cast<int>(u01(rng) * (c.max_steps - c.min_steps + 1));
    const double start_time = std::floor(u01(rng) * 1000.0) * dt;
    // Optional turning segment: [turn_begin, turn_end) steps with a constant turn rate.
    int turn_begin = steps, turn_end = steps;
    double omega = 0.0;
    if (u01(rng) < c.turn_probability) {
      turn_begin = static_cast<int>(u01(rng) * steps);
      turn_end = turn_begin + 4 + static_cast<int>(u01(rng) * 10);
      omega = (u01(rng) < 0.5 ? -1.0 : 1.0) * c.turn_rate_max * (0.5 + 0.5 * u01(rng));
    }
    Track t;
    t.agent_id = k;
    t.positions.resize(steps, 2);
    for (int i = 0; i < steps; ++i) {
      t.time.push_back(start_time + i * dt);
      t.positions.row(i) = (p + c.position_noise * Eigen::Vector2d(n01(rng), n01(rng))).transpose();
      if (i >= turn_begin && i < turn_end) heading += omega * dt;
      speed += c.speed_noise * n01(rng) + 0.2 * (preferred - speed);
      speed = std::clamp(speed, 0.5 * c.speed_min, 1.2 * c.speed_max);
      p += speed * dt * Eigen::Vector2d(std::cos(heading), std::sin(heading));
    }
    set.tracks.push_back(std::move(t));
  }
  return set;
}

}  // namespace foresight
