#include "datasets/map_tracks.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "core/log.h"
#include "datasets/crowd_replay.h"
#include "datasets/data_root.h"
#include "datasets/occ_traj.h"
#include "datasets/windows.h"

namespace foresight {
namespace {

constexpr double kBoundaryShift = 1e-9;  // OccTrajRaster: integer coordinates -> floor(.) cell

/// A named scene of a real dataset and its files relative to the data root.
struct SceneFiles {
  const char* name;
  const char* tracks;
  const char* image;
};
constexpr SceneFiles kThorScenes[] = {
    {"thor1", "thor/thor1_exp-1-run-2.csv", "thor/maps/thor1.png"},
    {"thor3", "thor/thor3_exp-3-run-2.csv", "thor/maps/thor3.png"},
};
constexpr SceneFiles kEthScenes[] = {
    {"seq_eth", "eth_ucy/eth_original/seq_eth/obsmat.txt", "eth_ucy/eth_original/seq_eth/map.png"},
    {"seq_hotel", "eth_ucy/eth_original/seq_hotel/obsmat.txt",
     "eth_ucy/eth_original/seq_hotel/map.png"},
};
constexpr const char* kOccTrajDir = "occ_traj120";
/// THOR map image extent (README: x in [-11, 12], y in [-10, 13.5]).
constexpr double kThorImage[4] = {-11.0, 12.0, -10.0, 13.5};

template <std::size_t N>
const SceneFiles* FindScene(const SceneFiles (&table)[N], const std::string& name) {
  for (const SceneFiles& s : table)
    if (name == s.name) return &s;
  return nullptr;
}

template <std::size_t N>
std::string SceneNames(const SceneFiles (&table)[N]) {
  std::string out;
  for (const SceneFiles& s : table) out += (out.empty() ? "" : ", ") + std::string(s.name);
  return out;
}

/// An Error naming the missing file and the keys that locate it.
void RequireFile(const std::string& path, const std::string& what, const std::string& root) {
  FS_THROW_UNLESS(std::filesystem::is_regular_file(path), "data.scenes: ", what, ": ", path,
                  " not found (data.root: '", root,
                  "'; empty = $FORESIGHT_DATA or ../shared/data)");
}

// ---- portable random numbers (std distributions are implementation-defined) ----------------
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  double Normal() {  // Box-Muller
    const double u1 = 1.0 - Uniform(), u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::mt19937_64 engine_;
};

std::uint64_t MixSeed(std::uint64_t seed, std::uint64_t index) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (index + 1);  // SplitMix64 finaliser
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Axis-aligned box [x0, x1] x [y0, y1] (m).
struct Box {
  double x0, x1, y0, y1;
  bool Contains(double x, double y, double margin = 0) const {
    return x >= x0 - margin && x <= x1 + margin && y >= y0 - margin && y <= y1 + margin;
  }
};

/// Extent of all samples: x_min, x_max, y_min, y_max.
Eigen::Vector4d BoundingBox(const TrackSet& set) {
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::Vector4d b(inf, -inf, inf, -inf);
  for (const Track& t : set.tracks)
    for (Eigen::Index i = 0; i < t.positions.rows(); ++i) {
      const double x = t.positions(i, 0), y = t.positions(i, 1);
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      b[0] = std::min(b[0], x);
      b[1] = std::max(b[1], x);
      b[2] = std::min(b[2], y);
      b[3] = std::max(b[3], y);
    }
  return b;
}

/// False (with a warning naming the scene) when no track has a finite sample: the scene is dropped.
bool HasFiniteSample(const TrackSet& set, const std::string& scene) {
  const Eigen::Vector4d b = BoundingBox(set);
  if (b[0] <= b[1] && b[2] <= b[3]) return true;
  log::Warn("scene '", scene, "' (", set.source, "): no track left after resampling; dropped");
  return false;
}

/// Bounding box + margin, snapped outwards to multiples of `resolution`.
Eigen::Vector4d MarginExtent(const TrackSet& set, double margin, double resolution,
                             const std::string& scene) {
  const Eigen::Vector4d b = BoundingBox(set);
  FS_THROW_UNLESS(b[0] <= b[1] && b[2] <= b[3], "scene '", scene, "' (", set.source,
                  "): no finite sample after resampling");
  return {std::floor((b[0] - margin) / resolution) * resolution,
          std::ceil((b[1] + margin) / resolution) * resolution,
          std::floor((b[2] - margin) / resolution) * resolution,
          std::ceil((b[3] + margin) / resolution) * resolution};
}

std::vector<MapScene> LoadThor(const MapTracksConfig& config) {
  std::vector<std::string> names = config.scenes;
  if (names.empty())
    for (const SceneFiles& s : kThorScenes) names.push_back(s.name);
  std::vector<MapScene> out;
  for (const std::string& name : names) {
    const SceneFiles* files = FindScene(kThorScenes, name);
    FS_THROW_UNLESS(files, "data.scenes: unknown thor scene '", name, "' (expected ",
                    SceneNames(kThorScenes), ")");
    const std::string csv = ResolveDataFile(config.root, files->tracks);
    const std::string png = ResolveDataFile(config.root, files->image);
    RequireFile(csv, "thor scene '" + name + "' tracks", config.root);
    RequireFile(png, "thor scene '" + name + "' map", config.root);
    MapScene scene;
    scene.name = name;
    scene.tracks = ResampleTracks(ReadThorTracks(csv), config.step, config.max_gap);
    if (!HasFiniteSample(scene.tracks, name)) continue;
    Eigen::Vector4d extent = MarginExtent(scene.tracks, 1.0, config.resolution, name);
    extent[0] = std::max(extent[0], kThorImage[0]);
    extent[1] = std::min(extent[1], kThorImage[1]);
    extent[2] = std::max(extent[2], kThorImage[2]);
    extent[3] = std::min(extent[3], kThorImage[3]);
    scene.raster = ThorMapRaster(png, extent, config.resolution);
    out.push_back(std::move(scene));
  }
  return out;
}

std::vector<MapScene> LoadEth(const MapTracksConfig& config) {
  std::vector<std::string> names = config.scenes;
  if (names.empty())
    for (const SceneFiles& s : kEthScenes) names.push_back(s.name);
  std::vector<MapScene> out;
  for (const std::string& name : names) {
    const SceneFiles* files = FindScene(kEthScenes, name);
    FS_THROW_UNLESS(files, "data.scenes: unknown eth scene '", name, "' (expected ",
                    SceneNames(kEthScenes), ")");
    const std::string obsmat = ResolveDataFile(config.root, files->tracks);
    const std::string png = ResolveDataFile(config.root, files->image);
    const std::string h =
        (std::filesystem::path(obsmat).parent_path() / "H.txt").string();  // beside obsmat.txt
    RequireFile(obsmat, "eth scene '" + name + "' tracks", config.root);
    RequireFile(png, "eth scene '" + name + "' map", config.root);
    RequireFile(h, "eth scene '" + name + "' homography", config.root);
    MapScene scene;
    scene.name = name;
    scene.tracks = ResampleTracks(ReadEthObsmat(obsmat), config.step, config.max_gap);
    if (!HasFiniteSample(scene.tracks, name)) continue;
    const Eigen::Vector4d extent = MarginExtent(scene.tracks, 2.0, config.resolution, name);
    scene.raster = EthMapRaster(png, ReadHomography(h), extent, config.resolution);
    out.push_back(std::move(scene));
  }
  return out;
}

/// Occ-Traj120 scenes; what the trajectory reader drops (outside the grid, fewer than 2
/// waypoints) is counted in `report` here, the rest by CheckSceneTracks.
std::vector<MapScene> LoadOccTraj(const MapTracksConfig& config, MapTracksReport* report) {
  const std::string dir = ResolveDataFile(config.root, kOccTrajDir);
  std::vector<std::string> ids = config.scenes;
  if (ids.empty()) {
    RequireFile(dir + "/train_maps.txt", "occ_traj map list", config.root);
    ids = otnet::ListOccTrajMaps(dir);
    if (static_cast<int>(ids.size()) > config.max_maps) ids.resize(config.max_maps);
  }
  const int subdivisions = static_cast<int>(std::lround(1.0 / config.resolution));
  std::vector<MapScene> out;
  for (const std::string& id : ids) {
    const std::string map_path = dir + "/maps/occtraj_" + id + "_map.txt";
    const std::string traj_path = dir + "/trajs/occtraj_" + id + "_trajs.txt";
    RequireFile(map_path, "occ_traj map '" + id + "'", config.root);
    RequireFile(traj_path, "occ_traj map '" + id + "' trajectories", config.root);
    const BinaryGrid grid = otnet::ReadOccTrajMap(map_path, 40, 40);
    // Read against an all-free grid: waypoints on obstacles are kept and counted afterwards.
    otnet::ReadReport read;
    const std::vector<Eigen::MatrixX2d> trajs = otnet::ReadOccTrajTrajectories(
        traj_path, BinaryGrid(grid.width, grid.height), otnet::BadWaypointPolicy::kDrop, &read);
    MapScene scene;
    scene.name = "occtraj_" + id;
    scene.raster = OccTrajRaster(grid, subdivisions);
    scene.tracks.source = traj_path;
    scene.tracks.seconds_per_step = 1.0;  // one waypoint per time unit (README)
    for (std::size_t k = 0; k < trajs.size(); ++k) {
      Track t;
      t.agent_id = static_cast<std::int64_t>(k);
      t.positions = trajs[k];
      t.time.resize(trajs[k].rows());
      for (Eigen::Index i = 0; i < trajs[k].rows(); ++i) t.time[i] = static_cast<double>(i);
      scene.tracks.tracks.push_back(std::move(t));
    }
    const int outside = read.dropped_outside + read.dropped_occupied;
    if (outside > 0)
      log::Warn("scene '", scene.name, "': ", outside, " of ", read.trajectories,
                " trajectories leave the 40 x 40 grid (dropped)");
    if (read.dropped_too_short > 0)
      log::Info("scene '", scene.name, "': ", read.dropped_too_short, " of ", read.trajectories,
                " trajectories have fewer than 2 waypoints (skipped)");
    if (report) {
      report->tracks_read += read.trajectories - read.kept;
      report->outside_frame += outside;
      report->too_short += read.dropped_too_short;
    }
    out.push_back(std::move(scene));
  }
  return out;
}

// ---- synthetic scenes ------------------------------------------------------------------------
constexpr double kSynthResolution = 0.1;  // m per cell
constexpr double kSynthStep = 0.4;        // s per sample
constexpr double kWall = 0.3;             // m, border wall thickness
constexpr double kClearance = 0.2;        // m, minimum distance of every sample to obstacles
constexpr double kMaxSpeed = 1.4, kMinSpeed = 1.0;  // m/s

/// Free with `kClearance` around (x, y): the point and 8 points on a circle of that radius.
bool FreeWithClearance(const OccupancyRaster& r, double x, double y) {
  if (r.Occupied(x, y)) return false;
  for (int k = 0; k < 8; ++k) {
    const double a = k * M_PI / 4;
    if (r.Occupied(x + kClearance * std::cos(a), y + kClearance * std::sin(a))) return false;
  }
  return true;
}

/// True when the segment a-b passes within `margin` of `box` (sampled every 5 cm).
bool SegmentNearBox(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Box& box,
                    double margin) {
  const int n = 1 + static_cast<int>((b - a).norm() / 0.05);
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / n);
    if (box.Contains(p.x(), p.y(), margin)) return true;
  }
  return false;
}

/// Chaikin corner cutting, endpoints kept.
std::vector<Eigen::Vector2d> Chaikin(const std::vector<Eigen::Vector2d>& p, int iterations) {
  std::vector<Eigen::Vector2d> cur = p;
  for (int it = 0; it < iterations && cur.size() > 2; ++it) {
    std::vector<Eigen::Vector2d> next{cur.front()};
    for (std::size_t i = 0; i + 1 < cur.size(); ++i) {
      const Eigen::Vector2d q = 0.75 * cur[i] + 0.25 * cur[i + 1];
      const Eigen::Vector2d r = 0.25 * cur[i] + 0.75 * cur[i + 1];
      if (i > 0) next.push_back(q);
      if (i + 2 < cur.size()) next.push_back(r);
    }
    next.push_back(cur.back());
    cur = std::move(next);
  }
  return cur;
}

/// One track along the polyline `path` (walked at speed v with 3 % step jitter, a smooth lateral
/// wander of <= 0.15 m and 1 cm noise); empty when a sample misses the clearance.
Eigen::Matrix<double, Eigen::Dynamic, 2> WalkPath(const std::vector<Eigen::Vector2d>& path,
                                                  const OccupancyRaster& raster, Rng* rng) {
  std::vector<double> cum{0.0};
  for (std::size_t i = 1; i < path.size(); ++i)
    cum.push_back(cum.back() + (path[i] - path[i - 1]).norm());
  const double v = rng->Uniform(kMinSpeed, kMaxSpeed);
  std::vector<Eigen::Vector2d> samples;
  double s = 0, offset = 0;
  std::size_t seg = 0;
  while (s <= cum.back()) {
    while (seg + 2 < path.size() && cum[seg + 1] < s) ++seg;
    const Eigen::Vector2d d = path[seg + 1] - path[seg];
    const double len = std::max(d.norm(), 1e-12);
    const Eigen::Vector2d p = path[seg] + d * ((s - cum[seg]) / len);
    const Eigen::Vector2d normal(-d.y() / len, d.x() / len);
    offset = std::clamp(0.85 * offset + 0.03 * rng->Normal(), -0.15, 0.15);
    const Eigen::Vector2d q =
        p + offset * normal + 0.01 * Eigen::Vector2d(rng->Normal(), rng->Normal());
    if (!FreeWithClearance(raster, q.x(), q.y())) return {};
    samples.push_back(q);
    s += v * kSynthStep * std::clamp(1.0 + 0.03 * rng->Normal(), 0.9, 1.1);
  }
  Eigen::Matrix<double, Eigen::Dynamic, 2> out(static_cast<Eigen::Index>(samples.size()), 2);
  for (std::size_t i = 0; i < samples.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = samples[i];
  return out;
}

MapScene GenerateScene(int index, int tracks, int min_points, std::uint64_t seed) {
  Rng rng(MixSeed(seed, static_cast<std::uint64_t>(index)));
  const double needed = (min_points - 1) * kMaxSpeed * kSynthStep * 1.15 + 2.5;  // start to goal
  const double width =
      std::ceil(std::max(rng.Uniform(14, 18), needed) / kSynthResolution) * kSynthResolution;
  const double height = std::ceil(rng.Uniform(10, 13) / kSynthResolution) * kSynthResolution;
  const double bx = width / 2 + rng.Uniform(-1, 1), by = height / 2 + rng.Uniform(-1, 1);
  const double hx = rng.Uniform(0.6, 1.5), hy = rng.Uniform(0.8, 2.0);
  const Box block{bx - hx, bx + hx, by - hy, by + hy};
  std::vector<Box> boxes{block,
                         {0, width, 0, kWall},
                         {0, width, height - kWall, height},
                         {0, kWall, 0, height},
                         {width - kWall, width, 0, height}};
  for (int p = 0, attempts = 0; p < 2 && attempts < 50; ++attempts) {
    const double h = rng.Uniform(0.25, 0.45);
    const double x = rng.Uniform(2.0, width - 2.0), y = rng.Uniform(1.5, height - 1.5);
    if (block.Contains(x, y, 1.5 + h)) continue;
    boxes.push_back({x - h, x + h, y - h, y + h});
    ++p;
  }

  MapScene scene;
  scene.name = "synthetic_" + std::to_string(index);
  OccupancyRaster& r = scene.raster;
  r.extent = Eigen::Vector4d(0, width, 0, height);
  r.resolution = kSynthResolution;
  r.cells.setZero(std::lround(height / kSynthResolution), std::lround(width / kSynthResolution));
  for (Eigen::Index row = 0; row < r.cells.rows(); ++row)
    for (Eigen::Index c = 0; c < r.cells.cols(); ++c) {
      const double x = (static_cast<double>(c) + 0.5) * kSynthResolution;
      const double y = height - (static_cast<double>(row) + 0.5) * kSynthResolution;
      for (const Box& b : boxes)
        if (b.Contains(x, y)) r.cells(row, c) = 1;
    }

  scene.tracks.source = "synthetic";
  scene.tracks.seconds_per_step = kSynthStep;
  const double edge = kWall + 0.6, lo_y = 1.0, hi_y = height - 1.0;
  for (int attempt = 0;
       static_cast<int>(scene.tracks.tracks.size()) < tracks && attempt < 50 * tracks; ++attempt) {
    const bool rightwards = rng.Uniform() < 0.5;
    // Half of the tracks start and end level with the block, so that it is in their way.
    const bool level = rng.Uniform() < 0.5;
    const auto draw_y = [&] {
      return level ? rng.Uniform(std::max(lo_y, block.y0), std::min(hi_y, block.y1))
                   : rng.Uniform(lo_y, hi_y);
    };
    Eigen::Vector2d start(rightwards ? edge : width - edge, draw_y());
    Eigen::Vector2d goal;
    if (rng.Uniform() < 0.75) {  // across the room
      goal = {rightwards ? width - edge : edge, draw_y()};
    } else {  // to the top or bottom wall of the far half
      const double gx =
          rightwards ? rng.Uniform(width / 2 + 1, width - edge) : rng.Uniform(edge, width / 2 - 1);
      goal = {gx, rng.Uniform() < 0.5 ? edge : height - edge};
    }
    std::vector<Eigen::Vector2d> path{start};
    const double clear = rng.Uniform(0.7, 1.2);
    if (SegmentNearBox(start, goal, block, clear)) {
      // Head for the block along the straight line, then swerve around it late, on the side
      // nearer the line (sometimes the other one), and rejoin the line behind it: a
      // constant-velocity extrapolation of the approach runs into the block.
      const double mid_y = 0.5 * (start.y() + goal.y());
      bool above = mid_y > by;
      if (rng.Uniform() < 0.25) above = !above;
      double vy = above ? block.y1 + clear : block.y0 - clear;
      if (vy < lo_y || vy > hi_y) vy = above ? block.y0 - clear : block.y1 + clear;
      const double dir = rightwards ? 1.0 : -1.0;
      const double near_x = rightwards ? block.x0 : block.x1;  // the face met first
      const double far_x = rightwards ? block.x1 : block.x0;
      const auto on_line = [&](double x) -> Eigen::Vector2d {
        return start + (goal - start) * ((x - start.x()) / (goal.x() - start.x()));
      };
      const double approach_x = near_x - dir * (clear + rng.Uniform(1.0, 2.5));
      if (dir * (approach_x - start.x()) > 0.5) path.push_back(on_line(approach_x));
      path.emplace_back(near_x - dir * 0.2, vy);
      path.emplace_back(far_x + dir * 0.2, vy);
      const double rejoin_x = far_x + dir * (clear + rng.Uniform(1.0, 2.5));
      if (dir * (goal.x() - rejoin_x) > 0.5) path.push_back(on_line(rejoin_x));
    }
    path.push_back(goal);
    Eigen::Matrix<double, Eigen::Dynamic, 2> positions = WalkPath(Chaikin(path, 3), r, &rng);
    if (positions.rows() < std::max(min_points, 2)) continue;
    Track t;
    t.agent_id = static_cast<std::int64_t>(scene.tracks.tracks.size());
    t.positions = std::move(positions);
    t.time.resize(t.positions.rows());
    for (std::size_t i = 0; i < t.time.size(); ++i) t.time[i] = kSynthStep * static_cast<double>(i);
    scene.tracks.tracks.push_back(std::move(t));
  }
  if (static_cast<int>(scene.tracks.tracks.size()) < tracks)
    log::Warn("scene '", scene.name, "': generated ", scene.tracks.tracks.size(), " of ", tracks,
              " tracks (the others missed the clearance or had fewer than ", min_points,
              " samples)");
  return scene;
}

}  // namespace

// ---- report ---------------------------------------------------------------------------------
void MapTracksReport::Add(const MapTracksReport& o) {
  scenes += o.scenes;
  tracks_read += o.tracks_read;
  tracks_kept += o.tracks_kept;
  too_short += o.too_short;
  outside_frame += o.outside_frame;
  points_in_obstacles += o.points_in_obstacles;
  tracks_in_obstacles += o.tracks_in_obstacles;
  points_kept += o.points_kept;
}

std::string MapTracksReport::BriefReport() const {
  std::ostringstream os;
  const double share = points_kept > 0 ? 100.0 * points_in_obstacles / points_kept : 0.0;
  os << scenes << " scenes, " << tracks_kept << "/" << tracks_read << " tracks kept (too short "
     << too_short << ", outside frame " << outside_frame << "), " << points_in_obstacles << " of "
     << points_kept << " samples (" << std::fixed << std::setprecision(2) << share << " %) in "
     << tracks_in_obstacles << " tracks on obstacles";
  return os.str();
}

// ---- config ---------------------------------------------------------------------------------
void MapTracksConfig::Validate(const std::string& where) const {
  static const std::set<std::string> kSources{"synthetic", "occ_traj", "thor", "eth"};
  FS_THROW_UNLESS(kSources.count(source), where, ": data.source: '", source,
                  "' is not one of synthetic, occ_traj, thor, eth");
  std::set<std::string> seen;
  for (const std::string& s : scenes) {
    FS_THROW_UNLESS(seen.insert(s).second, where, ": data.scenes: '", s, "' is listed twice");
    if (source == "thor")
      FS_THROW_UNLESS(FindScene(kThorScenes, s), where, ": data.scenes: unknown thor scene '", s,
                      "' (expected ", SceneNames(kThorScenes), ")");
    else if (source == "eth")
      FS_THROW_UNLESS(FindScene(kEthScenes, s), where, ": data.scenes: unknown eth scene '", s,
                      "' (expected ", SceneNames(kEthScenes), ")");
    else if (source == "occ_traj")
      FS_THROW_UNLESS(!s.empty() && s.find_first_of("/\\ ") == std::string::npos, where,
                      ": data.scenes: '", s, "' is not an Occ-Traj120 map id (e.g. 0209bae1c9)");
  }
  FS_THROW_UNLESS(source != "synthetic" || scenes.empty(), where,
                  ": data.scenes: the synthetic source has no named scenes (", scenes.size(),
                  " given); set data.max_maps instead");
  FS_THROW_UNLESS(std::isfinite(resolution) && resolution > 0, where,
                  ": data.resolution: ", resolution, " must be positive");
  if (source == "occ_traj") {
    const double k = std::round(1.0 / resolution);
    FS_THROW_UNLESS(k >= 1 && std::abs(k * resolution - 1.0) < 1e-9, where,
                    ": data.resolution: ", resolution,
                    " does not divide an Occ-Traj120 cell (use 1, 0.5, 0.25, 0.2, 0.1, ...)");
  }
  if (source == "thor" || source == "eth")
    FS_THROW_UNLESS(max_gap >= step, where, ": data.max_gap: ", max_gap, " s is below data.step ",
                    step, " s (every track would be split at every sample)");
}

// ---- scene checks ---------------------------------------------------------------------------
bool InsideRaster(const OccupancyRaster& raster, double x, double y) {
  const double c = std::floor((x - raster.extent[0]) / raster.resolution);
  const double r = std::floor((raster.extent[3] - y) / raster.resolution);
  return c >= 0 && r >= 0 && c < static_cast<double>(raster.cells.cols()) &&
         r < static_cast<double>(raster.cells.rows());
}

void CheckSceneTracks(MapScene* scene, int min_points, MapTracksReport* report) {
  MapTracksReport counts;
  std::vector<Track> kept;
  for (Track& t : scene->tracks.tracks) {
    ++counts.tracks_read;
    if (t.positions.rows() < min_points) {
      ++counts.too_short;
      continue;
    }
    bool inside = true;
    int on_obstacles = 0;
    for (Eigen::Index i = 0; i < t.positions.rows() && inside; ++i) {
      const double x = t.positions(i, 0), y = t.positions(i, 1);
      inside = std::isfinite(x) && std::isfinite(y) && InsideRaster(scene->raster, x, y);
      on_obstacles += inside && scene->raster.Occupied(x, y);
    }
    if (!inside) {
      ++counts.outside_frame;
      continue;
    }
    ++counts.tracks_kept;
    counts.points_kept += static_cast<int>(t.positions.rows());
    counts.points_in_obstacles += on_obstacles;
    counts.tracks_in_obstacles += on_obstacles > 0;
    kept.push_back(std::move(t));
  }
  scene->tracks.tracks = std::move(kept);
  const std::string& name = scene->name;
  if (counts.too_short > 0)
    log::Info("scene '", name, "': ", counts.too_short, " of ", counts.tracks_read,
              " tracks have fewer than ", min_points, " samples (skipped)");
  if (counts.outside_frame > 0) {
    const Eigen::Vector4d& e = scene->raster.extent;
    log::Warn("scene '", name, "': ", counts.outside_frame, " of ", counts.tracks_read,
              " tracks leave the map's extent x [", e[0], ", ", e[1], "], y [", e[2], ", ", e[3],
              "] (dropped: the map frame does not cover them)");
  }
  if (counts.points_in_obstacles > 0)
    log::Warn("scene '", name, "': ", counts.points_in_obstacles, " of ", counts.points_kept,
              " samples (", 100.0 * counts.points_in_obstacles / counts.points_kept, " %) in ",
              counts.tracks_in_obstacles,
              " tracks lie on occupied cells (kept; a map or "
              "homography misregistration?)");
  if (report) report->Add(counts);
}

OccupancyRaster OccTrajRaster(const BinaryGrid& grid, int subdivisions) {
  FS_THROW_UNLESS(subdivisions >= 1, "OccTrajRaster: subdivisions ", subdivisions, " must be >= 1");
  FS_THROW_UNLESS(grid.width > 0 && grid.height > 0 &&
                      grid.cells.size() == static_cast<std::size_t>(grid.width) * grid.height,
                  "OccTrajRaster: malformed grid ", grid.width, " x ", grid.height, " with ",
                  grid.cells.size(), " cells");
  OccupancyRaster r;
  r.extent = Eigen::Vector4d(-kBoundaryShift, grid.width - kBoundaryShift, -kBoundaryShift,
                             grid.height - kBoundaryShift);
  r.resolution = 1.0 / subdivisions;
  r.cells.resize(static_cast<Eigen::Index>(grid.height) * subdivisions,
                 static_cast<Eigen::Index>(grid.width) * subdivisions);
  for (Eigen::Index i = 0; i < r.cells.rows(); ++i)
    for (Eigen::Index j = 0; j < r.cells.cols(); ++j)
      r.cells(i, j) = grid.at(grid.height - 1 - static_cast<int>(i / subdivisions),
                              static_cast<int>(j / subdivisions)) != 0;
  return r;
}

// ---- loading --------------------------------------------------------------------------------
std::vector<MapScene> LoadMapScenes(const MapTracksConfig& config, int min_points,
                                    MapTracksReport* report) {
  config.Validate("map tracks config");
  FS_THROW_UNLESS(min_points >= 2, "LoadMapScenes: min_points ", min_points,
                  " must be >= 2 (observed + predicted samples)");
  MapTracksReport total;
  std::vector<MapScene> scenes;
  if (config.source == "synthetic")
    scenes = GenerateMapScenes(config.max_maps, config.synthetic_tracks, min_points,
                               static_cast<std::uint64_t>(config.synthetic_seed));
  else if (config.source == "occ_traj")
    scenes = LoadOccTraj(config, &total);
  else if (config.source == "thor")
    scenes = LoadThor(config);
  else
    scenes = LoadEth(config);

  std::vector<MapScene> out;
  for (MapScene& scene : scenes) {
    CheckSceneTracks(&scene, min_points, &total);
    if (scene.tracks.tracks.empty()) {
      log::Warn("scene '", scene.name, "': no track of >= ", min_points,
                " samples inside the map (scene dropped)");
      continue;
    }
    out.push_back(std::move(scene));
  }
  total.scenes = static_cast<int>(out.size());
  FS_THROW_UNLESS(!out.empty(), "data.source ", config.source, ": none of ", scenes.size(),
                  " scenes has a track of >= ", min_points,
                  " samples inside its map (data.scenes, data.max_gap; ", total.BriefReport(), ")");
  log::Info("map tracks (", config.source, "): ", total.BriefReport());
  if (report) report->Add(total);
  return out;
}

std::vector<MapScene> GenerateMapScenes(int maps, int tracks_per_map, int min_points,
                                        std::uint64_t seed) {
  FS_THROW_UNLESS(maps >= 1, "GenerateMapScenes: maps ", maps, " must be >= 1");
  FS_THROW_UNLESS(tracks_per_map >= 1, "GenerateMapScenes: tracks_per_map ", tracks_per_map,
                  " must be >= 1");
  FS_THROW_UNLESS(min_points >= 2 && min_points <= 200, "GenerateMapScenes: min_points ",
                  min_points, " is outside [2, 200]");
  std::vector<MapScene> out;
  out.reserve(maps);
  for (int k = 0; k < maps; ++k) out.push_back(GenerateScene(k, tracks_per_map, min_points, seed));
  return out;
}

MapTracksSplit SplitMapScenes(const std::vector<MapScene>& scenes, bool by_scene,
                              double val_fraction, double test_fraction, std::uint64_t seed) {
  MapTracksSplit out;
  if (by_scene) {
    std::vector<std::string> names;
    std::unordered_map<std::string, std::size_t> index;
    for (std::size_t i = 0; i < scenes.size(); ++i) {
      names.push_back(scenes[i].name);
      index[scenes[i].name] = i;
    }
    const otnet::MapSplit split = otnet::SplitMaps(names, val_fraction, test_fraction, seed);
    for (const std::string& n : split.train) out.train.push_back(scenes[index.at(n)]);
    for (const std::string& n : split.val) out.val.push_back(scenes[index.at(n)]);
    for (const std::string& n : split.test) out.test.push_back(scenes[index.at(n)]);
    return out;
  }
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const MapScene& s = scenes[i];
    // Split agents, not pieces: ResampleTracks cuts a track at gaps into pieces that share the
    // agent id, and one pedestrian must not be both trained on and scored.
    TrackSet agents;
    agents.source = s.tracks.source;
    agents.seconds_per_step = s.tracks.seconds_per_step;
    std::unordered_map<std::int64_t, std::size_t> agent_index;
    for (const Track& t : s.tracks.tracks)
      if (agent_index.emplace(t.agent_id, agents.tracks.size()).second) {
        Track a;
        a.agent_id = t.agent_id;
        agents.tracks.push_back(std::move(a));
      }
    const TrackSplit by_agent = SplitTracks(agents, val_fraction, test_fraction, MixSeed(seed, i));
    std::unordered_map<std::int64_t, int> part_of;
    for (const Track& a : by_agent.val.tracks) part_of[a.agent_id] = 1;
    for (const Track& a : by_agent.test.tracks) part_of[a.agent_id] = 2;
    TrackSplit split;
    for (TrackSet* d : {&split.train, &split.val, &split.test}) {
      d->source = s.tracks.source;
      d->seconds_per_step = s.tracks.seconds_per_step;
    }
    for (const Track& t : s.tracks.tracks) {
      const auto it = part_of.find(t.agent_id);
      const int part = it == part_of.end() ? 0 : it->second;
      (part == 1 ? split.val : part == 2 ? split.test : split.train).tracks.push_back(t);
    }
    const auto add = [&s](TrackSet&& part, std::vector<MapScene>* dst) {
      if (part.tracks.empty()) return;
      dst->push_back(MapScene{s.name, s.raster, std::move(part)});
    };
    add(std::move(split.train), &out.train);
    add(std::move(split.val), &out.val);
    add(std::move(split.test), &out.test);
  }
  return out;
}

}  // namespace foresight
