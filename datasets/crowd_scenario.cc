#include "datasets/crowd_scenario.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "datasets/crowd_replay.h"
#include "datasets/crowd_sim.h"

namespace foresight {
namespace {

bool Finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double d) { return std::isfinite(d); });
}

std::string Join(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + internal::Concat(v[i]);
  return s + "]";
}

/// A box [x_min, x_max, y_min, y_max] (degenerate allowed) inside `extent`.
void CheckBox(const std::vector<double>& box, const std::vector<double>& extent,
              const std::string& where, const std::string& key) {
  FS_THROW_UNLESS(box.size() == 4 && Finite(box), where, ": '", key,
                  "' must be 4 finite numbers [x_min, x_max, y_min, y_max], got ", Join(box));
  FS_THROW_UNLESS(box[0] <= box[1] && box[2] <= box[3], where, ": '", key, "' = ", Join(box),
                  " is malformed (x_min > x_max or y_min > y_max)");
  FS_THROW_UNLESS(
      box[0] >= extent[0] && box[1] <= extent[1] && box[2] >= extent[2] && box[3] <= extent[3],
      where, ": '", key, "' = ", Join(box), " is not inside the extent ", Join(extent));
}

}  // namespace

PowerLawParams PowerLawParams::Aggressive() {
  PowerLawParams p;
  p.k = 1.5;
  p.exponent = 2.0;
  p.tau0 = 1.5;        // half the PRL horizon: react to imminent collisions only
  p.relaxation = 0.3;  // snap back to the goal velocity faster than the PRL 0.54 s
  p.max_accel = 20.0;
  p.max_speed = 1.0;
  return p;
}

void CrowdScenarioConfig::Validate(const std::string& where) const {
  FS_THROW_UNLESS(extent.size() == 4 && Finite(extent), where,
                  ": 'extent' must be 4 finite numbers ", "[x_min, x_max, y_min, y_max], got ",
                  Join(extent));
  FS_THROW_UNLESS(extent[0] < extent[1] && extent[2] < extent[3], where,
                  ": 'extent' = ", Join(extent), " is empty (x_min >= x_max or y_min >= y_max)");
  FS_THROW_UNLESS(robot_start.size() == 3 && Finite(robot_start), where,
                  ": 'robot_start' must be [x, y, heading], got ", Join(robot_start));
  FS_THROW_UNLESS(robot_goal.size() == 2 && Finite(robot_goal), where,
                  ": 'robot_goal' must be [x, y], got ", Join(robot_goal));
  const double margin = robot_radius + start_jitter;
  for (const auto& [key, pt] :
       {std::pair<const char*, const std::vector<double>*>{"robot_start", &robot_start},
        {"robot_goal", &robot_goal}}) {
    const double x = (*pt)[0], y = (*pt)[1];
    FS_THROW_UNLESS(x - margin >= extent[0] && x + margin <= extent[1] && y - margin >= extent[2] &&
                        y + margin <= extent[3],
                    where, ": '", key, "' = (", x, ", ", y, ") with robot radius ", robot_radius,
                    " and start_jitter ", start_jitter, " is not inside the extent ", Join(extent));
  }
  if (source == CrowdSource::kSimulated) {
    FS_THROW_UNLESS(!groups.empty(), where, ": simulated scenario '", name,
                    "' has no pedestrian groups (empty crowd); add 'groups'");
    for (std::size_t g = 0; g < groups.size(); ++g) {
      const std::string key = "groups[" + std::to_string(g) + "]";
      FS_THROW_UNLESS(groups[g].count >= 1, where, ": '", key, ".count' must be >= 1, got ",
                      groups[g].count);
      // The simulator caps |v| at max_speed: a faster preferred speed would be cut silently.
      FS_THROW_UNLESS(
          groups[g].preferred_speed + groups[g].speed_jitter <= power_law.max_speed + 1e-9, where,
          ": '", key, ".preferred_speed' = ", groups[g].preferred_speed, " + speed_jitter ",
          groups[g].speed_jitter,
          " exceeds the simulator's limit power_law.max_speed = ", power_law.max_speed, " m/s");
      CheckBox(groups[g].spawn, extent, where, key + ".spawn");
      CheckBox(groups[g].goal, extent, where, key + ".goal");
    }
    const double tol = 1e-9;
    for (std::size_t i = 0; i < walls.size(); ++i) {
      const WallSegment& w = walls[i];
      const std::string key = "walls[" + std::to_string(i) + "]";
      FS_THROW_UNLESS(Finite({w.x0, w.y0, w.x1, w.y1}), where, ": '", key,
                      "' has a non-finite coordinate");
      for (const auto& [x, y] : {std::pair<double, double>{w.x0, w.y0}, {w.x1, w.y1}})
        FS_THROW_UNLESS(x >= extent[0] - tol && x <= extent[1] + tol && y >= extent[2] - tol &&
                            y <= extent[3] + tol,
                        where, ": '", key, "' end (", x, ", ", y, ") is outside the extent ",
                        Join(extent));
      for (const auto& [key2, pt] :
           {std::pair<const char*, const std::vector<double>*>{"robot_start", &robot_start},
            {"robot_goal", &robot_goal}}) {
        const double d = DistanceToSegment({(*pt)[0], (*pt)[1]}, {w.x0, w.y0}, {w.x1, w.y1});
        FS_THROW_UNLESS(d >= robot_radius + 0.5 * wall_thickness, where, ": '", key2, "' = (",
                        (*pt)[0], ", ", (*pt)[1], ") is in collision with '", key, "' (distance ",
                        d, " m < robot radius ", robot_radius, " + half wall thickness ",
                        0.5 * wall_thickness, ")");
      }
    }
  } else {
    FS_THROW_UNLESS(replay.format == "thor" || replay.format == "eth_obsmat", where,
                    ": 'replay.format' = '", replay.format,
                    "' is unknown (expected thor or eth_obsmat)");
    FS_THROW_UNLESS(!replay.file.empty(), where, ": 'replay.file' is empty");
    FS_THROW_UNLESS(!replay.map_image.empty(), where, ": 'replay.map_image' is empty");
    FS_THROW_UNLESS(replay.step > 0 && replay.duration > replay.step, where,
                    ": 'replay.duration' must exceed 'replay.step'");
  }
}

CrowdScenarioConfig Sim1Scenario() {
  CrowdScenarioConfig s;
  s.name = "sim1";
  s.source = CrowdSource::kSimulated;
  s.extent = {-10, 10, -4, 4};
  // A partition at x = 0 with a 2 m doorway in the middle: the only way from one half to the other.
  s.walls = {{0, -4, 0, -1}, {0, 1, 0, 4}};
  s.wall_thickness = 0.2;
  PedestrianGroupConfig east;  // left half -> right half and back
  east.count = 12;
  east.spawn = {-7.5, -1.5, -3.5, 3.5};
  east.goal = {1.5, 7.5, -3.5, 3.5};
  east.preferred_speed = 0.9;
  east.speed_jitter = 0.1;
  east.round_trip = true;
  PedestrianGroupConfig west = east;  // the opposing flow
  west.spawn = east.goal;
  west.goal = east.spawn;
  s.groups = {east, west};
  s.pedestrian_radius = 0.4;
  s.power_law = PowerLawParams::Aggressive();
  s.robot_start = {-9, 0, 0};
  s.robot_goal = {9, 0};
  s.start_jitter = 0.3;
  s.replay = ReplayConfig{};
  return s;
}

CrowdScenarioConfig Sim2Scenario() {
  CrowdScenarioConfig s;
  s.name = "sim2";
  s.source = CrowdSource::kSimulated;
  s.extent = {-10, 10, -10, 10};
  s.walls.clear();
  PedestrianGroupConfig g;
  g.count = 6;
  g.preferred_speed = 0.9;
  g.speed_jitter = 0.1;
  g.round_trip = true;
  const std::vector<double> west{-9.5, -6.5, -5, 5}, east{6.5, 9.5, -5, 5},
      south{-5, 5, -9.5, -6.5}, north{-5, 5, 6.5, 9.5};
  for (const auto& [from, to] :
       {std::pair{west, east}, {east, west}, {south, north}, {north, south}}) {
    g.spawn = from;
    g.goal = to;
    s.groups.push_back(g);
  }
  s.pedestrian_radius = 0.4;
  s.power_law = PowerLawParams::Aggressive();
  s.robot_start = {-8.5, -8.5, M_PI / 4};
  s.robot_goal = {8.5, 8.5};
  s.start_jitter = 0.3;
  return s;
}

CrowdScenarioConfig DatasetScenario() {
  CrowdScenarioConfig s;
  s.name = "dataset";
  s.source = CrowdSource::kReplay;
  s.extent = {-11, 12, -10, 13.5};
  s.walls.clear();
  s.groups.clear();
  s.robot_start = {-3.5, -3, std::atan2(8.5, 7.0)};
  s.robot_goal = {3.5, 5.5};
  s.start_jitter = 0.3;
  s.replay = ReplayConfig{};  // thor1, 0.1 s, 3 windows of 60 s, 60 s apart
  return s;
}

std::unique_ptr<Crowd> MakeCrowd(const CrowdScenarioConfig& scenario, std::uint64_t episode_seed) {
  scenario.Validate("crowd scenario '" + scenario.name + "'");
  if (scenario.source == CrowdSource::kReplay)
    return std::make_unique<ReplayCrowd>(scenario, episode_seed);
  return std::make_unique<PowerLawCrowd>(scenario, episode_seed);
}

EpisodeEndpoints MakeEpisodeEndpoints(const CrowdScenarioConfig& s, std::uint64_t episode_seed) {
  EpisodeEndpoints e;
  e.start = Eigen::Vector3d(s.robot_start[0], s.robot_start[1], s.robot_start[2]);
  e.goal = Eigen::Vector2d(s.robot_goal[0], s.robot_goal[1]);
  if (s.start_jitter > 0) {
    std::mt19937_64 rng(episode_seed ^ 0x5deece66dULL);  // a stream apart from the crowd's
    std::uniform_real_distribution<double> u(-s.start_jitter, s.start_jitter);
    e.start.x() += u(rng);
    e.start.y() += u(rng);
    e.goal.x() += u(rng);
    e.goal.y() += u(rng);
  }
  return e;
}

bool OccupancyRaster::Occupied(double x, double y) const {
  const double c = std::floor((x - extent[0]) / resolution);
  const double r = std::floor((extent[3] - y) / resolution);
  if (!(c >= 0 && r >= 0 && c < cells.cols() && r < cells.rows())) return true;
  return cells(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) != 0;
}

OccupancyRaster ScenarioOccupancy(const CrowdScenarioConfig& s, double resolution) {
  s.Validate("crowd scenario '" + s.name + "'");
  if (s.source == CrowdSource::kReplay) return ReplayOccupancy(s, resolution);
  FS_THROW_UNLESS(std::isfinite(resolution) && resolution > 0,
                  "ScenarioOccupancy: resolution must be positive, got ", resolution);
  OccupancyRaster r;
  r.extent = Eigen::Vector4d(s.extent[0], s.extent[1], s.extent[2], s.extent[3]);
  r.resolution = resolution;
  const auto cols =
      static_cast<Eigen::Index>(std::ceil((s.extent[1] - s.extent[0]) / resolution - 1e-9));
  const auto rows =
      static_cast<Eigen::Index>(std::ceil((s.extent[3] - s.extent[2]) / resolution - 1e-9));
  r.cells.setZero(rows, cols);
  // A cell is a wall when its centre is within half the thickness (plus half a cell) of a segment.
  const double reach = 0.5 * s.wall_thickness + 0.5 * resolution;
  for (Eigen::Index row = 0; row < rows; ++row)
    for (Eigen::Index c = 0; c < cols; ++c) {
      const Eigen::Vector2d p(s.extent[0] + (static_cast<double>(c) + 0.5) * resolution,
                              s.extent[3] - (static_cast<double>(row) + 0.5) * resolution);
      for (const WallSegment& w : s.walls)
        if (DistanceToSegment(p, {w.x0, w.y0}, {w.x1, w.y1}) <= reach) {
          r.cells(row, c) = 1;
          break;
        }
    }
  return r;
}

TrackSet RecordCrowdTracks(const CrowdScenarioConfig& scenario, int episodes, double duration,
                           double step, std::uint64_t seed) {
  FS_THROW_UNLESS(episodes >= 1, "RecordCrowdTracks: episodes must be >= 1, got ", episodes);
  FS_THROW_UNLESS(std::isfinite(step) && step > 0 && std::isfinite(duration) && duration >= step,
                  "RecordCrowdTracks: need 0 < step <= duration, got step ", step, ", duration ",
                  duration);
  TrackSet set;
  set.source = "crowd:" + scenario.name;
  set.seconds_per_step = step;
  RobotAgent robot;
  robot.present = false;
  const int samples = static_cast<int>(std::floor(duration / step + 1e-9)) + 1;
  std::int64_t next_id = 0;
  for (int e = 0; e < episodes; ++e) {
    const std::unique_ptr<Crowd> crowd =
        MakeCrowd(scenario, seed * 1000003ULL + static_cast<std::uint64_t>(e));
    const std::size_t n = crowd->agents().size();
    // Per agent: the track piece being recorded (consecutive active samples).
    std::vector<Track> open(n);
    auto close = [&](std::size_t i) {
      if (open[i].size() >= 2) {
        open[i].agent_id = next_id++;
        set.tracks.push_back(std::move(open[i]));
      }
      open[i] = Track{};
    };
    std::vector<std::vector<Eigen::Vector2d>> points(n);
    for (int k = 0; k < samples; ++k) {
      if (k > 0) crowd->Step(step, robot);
      const double t = k * step;
      for (std::size_t i = 0; i < n; ++i) {
        const CrowdAgent& a = crowd->agents()[i];
        if (!a.active) {
          if (!points[i].empty()) {
            open[i].positions.resize(static_cast<Eigen::Index>(points[i].size()), 2);
            for (std::size_t j = 0; j < points[i].size(); ++j)
              open[i].positions.row(j) = points[i][j].transpose();
            points[i].clear();
          }
          close(i);
          continue;
        }
        open[i].time.push_back(t);
        points[i].push_back(a.position);
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      open[i].positions.resize(static_cast<Eigen::Index>(points[i].size()), 2);
      for (std::size_t j = 0; j < points[i].size(); ++j)
        open[i].positions.row(j) = points[i][j].transpose();
      close(i);
    }
  }
  return set;
}

}  // namespace foresight
