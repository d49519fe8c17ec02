#pragma once
/// Crowd scenarios for anticipatory navigation (SPAN, thesis ch. 5): a YAML-configured scene
/// (extent, walls, pedestrian groups, robot start and goal) whose crowd is either simulated with
/// the power-law model (Karamouzas, Skinner, Guy, PRL 2014; pedestrians react to the robot) or
/// replayed from recorded tracks (THOR, ETH obsmat; replayed pedestrians do not react).
///
/// Frames: every position is in the scenario's world frame (metres), velocities in m/s.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/tracks.h"

namespace foresight {

/// A straight wall from (x0, y0) to (x1, y1) (m), thickened by CrowdScenarioConfig::wall_thickness.
struct WallSegment {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  template <class A>
  void Serialize(A* a) {
    a->Visit("x0", &x0, config::Range::Any(), "start x (m)");
    a->Visit("y0", &y0, config::Range::Any(), "start y (m)");
    a->Visit("x1", &x1, config::Range::Any(), "end x (m)");
    a->Visit("y1", &y1, config::Range::Any(), "end y (m)");
  }
};

/// Parameters of the force-based power-law model (Karamouzas, Skinner, Guy, "Universal power law
/// governing pedestrian interactions", PRL 113, 238701, 2014). Defaults are the paper's / reference
/// code's values (k 1.5, exponent 2, tau0 3 s, relaxation 0.54 s, max accel 20 m/s^2, neighbour 10
/// m) with the maximum speed of 1 m/s.
struct PowerLawParams {
  double k = 1.5;         ///< energy scale k (m^2/s^2 per unit mass)
  double exponent = 2.0;  ///< power-law exponent of tau in E(tau) = k tau^-exponent exp(-tau/tau0)
  double tau0 = 3.0;      ///< s, exponential cut-off of the interaction horizon
  double relaxation = 0.54;     ///< s, goal-velocity relaxation time (xi of the PRL code)
  double max_accel = 20.0;      ///< m/s^2, cap on |dv/dt|
  double max_speed = 1.0;       ///< m/s, cap on |v|
  double neighbor_dist = 10.0;  ///< m, only neighbours (and walls) within this distance interact
  double wall_k = 1.5;          ///< energy scale of the time-to-collision energy with walls
  double wall_contact_stiffness = 50.0;  ///< 1/s^2, short-range push-out once a disc touches a wall
  double tau_min = 0.05;                 ///< s, tau is clamped below at this value (bounded forces)
  double substep = 0.02;                 ///< s, integration step inside Crowd::Step

  template <class A>
  void Serialize(A* a) {
    a->Visit("k", &k, config::Range::NonNegative(), "energy scale k of the pedestrian interaction");
    a->Visit("exponent", &exponent, config::Range::Positive(), "power-law exponent of tau");
    a->Visit("tau0", &tau0, config::Range::Positive(), "exponential cut-off time tau0 (s)");
    a->Visit("relaxation", &relaxation, config::Range::Positive(),
             "goal-velocity relaxation time xi (s)");
    a->Visit("max_accel", &max_accel, config::Range::Positive(), "maximum acceleration (m/s^2)");
    a->Visit("max_speed", &max_speed, config::Range::Positive(), "maximum speed (m/s)");
    a->Visit("neighbor_dist", &neighbor_dist, config::Range::Positive(),
             "interaction range for pedestrians, the robot and walls (m)");
    a->Visit("wall_k", &wall_k, config::Range::NonNegative(),
             "energy scale of the time-to-collision interaction with walls");
    a->Visit("wall_contact_stiffness", &wall_contact_stiffness, config::Range::NonNegative(),
             "push-out stiffness on wall contact (1/s^2)");
    a->Visit("tau_min", &tau_min, config::Range::Positive(), "lower clamp of tau (s)");
    a->Visit("substep", &substep, config::Range::OpenClosed(0, 0.1), "integration substep (s)");
  }

  /// The "aggressive" set used for the navigation scenarios: pedestrians look ahead half as far
  /// (tau0 1.5 s instead of 3 s) and return to their goal velocity faster (relaxation 0.3 s
  /// instead of 0.54 s), so they yield late and little and keep pushing through bottlenecks;
  /// k 1.5, exponent 2, max accel 20 m/s^2 as in the PRL code; max speed 1 m/s (the issue's).
  static PowerLawParams Aggressive();
};

/// A group of pedestrians spawned in one box and walking to random points of another.
struct PedestrianGroupConfig {
  int count = 1;
  std::vector<double> spawn{-1, 1, -1,
                            1};            ///< x_min, x_max, y_min, y_max (m); degenerate = a point
  std::vector<double> goal{-1, 1, -1, 1};  ///< x_min, x_max, y_min, y_max (m)
  /// m/s; with the jitter at most PowerLawParams::max_speed (Validate refuses faster groups)
  double preferred_speed = 0.9;
  double speed_jitter = 0.1;  ///< m/s, uniform +- jitter of each pedestrian's speed
  double radius = 0.0;        ///< m, 0 = CrowdScenarioConfig::pedestrian_radius
  /// On reaching the goal, walk back to a new point of the spawn box (and so on), so the density
  /// persists; otherwise stop at the goal (the pedestrian stays, as an obstacle).
  bool round_trip = true;

  template <class A>
  void Serialize(A* a) {
    a->Visit("count", &count, config::Range::AtLeast(1), "number of pedestrians");
    a->Visit("spawn", &spawn, config::Range::Any(), "spawn box [x_min, x_max, y_min, y_max] (m)");
    a->Visit("goal", &goal, config::Range::Any(), "goal box [x_min, x_max, y_min, y_max] (m)");
    a->Visit("preferred_speed", &preferred_speed, config::Range::Positive(),
             "preferred speed (m/s)");
    a->Visit("speed_jitter", &speed_jitter, config::Range::NonNegative(),
             "uniform +- jitter of the preferred speed per pedestrian (m/s)");
    a->Visit("radius", &radius, config::Range::NonNegative(),
             "pedestrian radius (m); 0 = the scenario's pedestrian_radius");
    a->Visit("round_trip", &round_trip, config::Range::Any(),
             "walk back and forth between the boxes instead of stopping at the goal");
  }
};

enum class CrowdSource { kSimulated, kReplay };

/// Replay of recorded pedestrians (scenario `dataset`).
struct ReplayConfig {
  std::string format = "thor";  ///< thor | eth_obsmat
  std::string file = "thor/thor1_exp-1-run-2.csv";
  std::string map_image = "thor/maps/thor1.png";
  std::string homography;  ///< eth_obsmat: H.txt (image -> world); empty = H.txt beside `file`
  std::string root;        ///< data root for relative names; empty = datasets/data_root.h default
  double step = 0.1;       ///< s, tracks are interpolated to this step
  int overlays = 3;        ///< number of time windows overlaid
  double overlay_spacing = 60;  ///< s between the starts of overlaid windows
  double duration = 60;         ///< s, length of each window

  template <class A>
  void Serialize(A* a) {
    a->Visit("format", &format, config::Range::Any(), "track format: thor | eth_obsmat");
    a->Visit("file", &file, config::Range::Any(), "track file (relative to root)");
    a->Visit("map_image", &map_image, config::Range::Any(), "obstacle image (relative to root)");
    a->Visit("homography", &homography, config::Range::Any(),
             "eth_obsmat: H.txt; empty = H.txt in the track file's folder");
    a->Visit("root", &root, config::Range::Any(),
             "data root; empty = $FORESIGHT_DATA or ../shared/data");
    a->Visit("step", &step, config::Range::Positive(), "interpolation step (s)");
    a->Visit("overlays", &overlays, config::Range::AtLeast(1), "time windows overlaid");
    a->Visit("overlay_spacing", &overlay_spacing, config::Range::NonNegative(),
             "time between the starts of overlaid windows (s)");
    a->Visit("duration", &duration, config::Range::Positive(), "window length (s)");
  }
};

struct CrowdScenarioConfig {
  std::string name = "sim1";
  CrowdSource source = CrowdSource::kSimulated;
  std::vector<double> extent{-10, 10, -4, 4};  ///< x_min, x_max, y_min, y_max (m); outside = wall
  std::vector<WallSegment> walls;
  double wall_thickness = 0.2;  ///< m, full thickness of every wall
  std::vector<PedestrianGroupConfig> groups;
  double pedestrian_radius = 0.4;  ///< m
  PowerLawParams power_law = PowerLawParams::Aggressive();
  std::vector<double> robot_start{-8, 0, 0};  ///< x, y (m), heading (rad)
  std::vector<double> robot_goal{8, 0};       ///< x, y (m)
  double robot_radius = 0.4;                  ///< m
  double start_jitter = 0.0;  ///< m, per-episode uniform shift of start and goal in each coordinate
  ReplayConfig replay;

  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &name, config::Range::Any(), "scenario name");
    a->VisitEnum("source", &source,
                 config::EnumNames<CrowdSource>{{CrowdSource::kSimulated, "simulated"},
                                                {CrowdSource::kReplay, "replay"}},
                 "simulated power-law crowd or replayed recorded tracks");
    a->Visit("extent", &extent, config::Range::Any(),
             "scene box [x_min, x_max, y_min, y_max] (m); outside is occupied");
    a->Visit("walls", &walls, config::Range::Any(), "wall segments (simulated scenes)");
    a->Visit("wall_thickness", &wall_thickness, config::Range::Positive(), "wall thickness (m)");
    a->Visit("groups", &groups, config::Range::Any(), "pedestrian groups (simulated scenes)");
    a->Visit("pedestrian_radius", &pedestrian_radius, config::Range::Positive(),
             "pedestrian radius (m)");
    a->Visit("power_law", &power_law, config::Range::Any(), "power-law model parameters");
    a->Visit("robot_start", &robot_start, config::Range::Any(),
             "robot start [x, y, heading] (m, rad)");
    a->Visit("robot_goal", &robot_goal, config::Range::Any(), "robot goal [x, y] (m)");
    a->Visit("robot_radius", &robot_radius, config::Range::Positive(), "robot radius (m)");
    a->Visit("start_jitter", &start_jitter, config::Range::NonNegative(),
             "per-episode random shift of start and goal (m)");
    a->Visit("replay", &replay, config::Range::Any(), "replayed tracks (source: replay)");
  }

  /// Throws foresight::Error naming `where` (a file or config path) for inconsistent scenes:
  /// malformed extent or boxes, start/goal outside the extent or inside a wall, walls outside the
  /// extent, a simulated scene without pedestrians, an unknown replay format.
  void Validate(const std::string& where) const;
};

/// The `sim1` default: a 20 m x 8 m hall split by a wall with a 2 m central doorway; two opposing
/// flows of 12 pedestrians each go through the doorway (round trips) while the robot crosses the
/// hall through the same doorway -> congestion. Note: the shipped configs/navigation/sim1.yaml is
/// a different scene (two flows crossing a 20 m x 10 m hall with two pillars): here the flows clog
/// the doorway for minutes, so no controller gets through without pushing; this one stays as the
/// simulator's test scene.
CrowdScenarioConfig Sim1Scenario();
/// The `sim2` default: an open 20 m x 20 m area with 24 pedestrians in four loosely crossing flows.
CrowdScenarioConfig Sim2Scenario();
/// The `dataset` default: THOR run thor1 (../shared/data/thor) replayed with 3 overlaid 60 s
/// windows 60 s apart on the room's map (extent x in [-11, 12], y in [-10, 13.5]); the robot
/// crosses the room diagonally from (-3.5, -3) to (3.5, 5.5), past the central obstacle.
CrowdScenarioConfig DatasetScenario();

/// One pedestrian at the crowd's current time.
struct CrowdAgent {
  std::int64_t id = 0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  ///< m, world
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  ///< m/s, world
  double radius = 0.4;                                 ///< m
  bool active = true;  ///< replay: the track covers the current time; simulated: always true
};

/// The robot as the crowd sees it (simulated pedestrians treat it as one more neighbour).
struct RobotAgent {
  Eigen::Vector2d position = Eigen::Vector2d::Zero(), velocity = Eigen::Vector2d::Zero();
  double radius = 0.4;
  bool present = true;  ///< false: pedestrians ignore the robot (e.g. recording training tracks)
};

/// A crowd that advances in time; simulated agents react to the robot, replayed ones do not.
class Crowd {
 public:
  virtual ~Crowd() = default;
  /// Advances by `dt` s (e.g. 0.1 s; internally substeps as needed).
  virtual void Step(double dt, const RobotAgent& robot) = 0;
  /// s since the start of the episode.
  virtual double time() const = 0;
  /// Every pedestrian; inactive ones (replay: not yet/no longer present) have active = false.
  virtual const std::vector<CrowdAgent>& agents() const = 0;
};

/// The crowd of one episode. Deterministic in (scenario, episode_seed); the scenario is validated.
std::unique_ptr<Crowd> MakeCrowd(const CrowdScenarioConfig& scenario, std::uint64_t episode_seed);

/// Robot start [x, y, heading] and goal [x, y] of one episode (start_jitter applied, seeded).
struct EpisodeEndpoints {
  Eigen::Vector3d start;
  Eigen::Vector2d goal;
};
EpisodeEndpoints MakeEpisodeEndpoints(const CrowdScenarioConfig& scenario,
                                      std::uint64_t episode_seed);

/// Static occupancy of the scenario as a raster (row 0 = y_max, col 0 = x_min, 1 = occupied).
struct OccupancyRaster {
  Eigen::Vector4d extent = Eigen::Vector4d::Zero();  ///< x_min, x_max, y_min, y_max (m)
  double resolution = 0.05;                          ///< m per cell
  Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> cells;
  /// The cell containing (x, y); outside the raster counts as occupied.
  bool Occupied(double x, double y) const;
};

/// Walls with thickness and the outside of the extent for simulated scenes; the obstacle image
/// (THOR png / ETH map.png through H) for replays, resampled to `resolution` (m per cell).
OccupancyRaster ScenarioOccupancy(const CrowdScenarioConfig& scenario, double resolution);

/// Tracks of simulated pedestrians (no robot) for training the SPAN predictor: `episodes` seeded
/// runs of `duration` s sampled every `step` s. One track per pedestrian and episode (ids unique).
TrackSet RecordCrowdTracks(const CrowdScenarioConfig& scenario, int episodes, double duration,
                           double step, std::uint64_t seed);

}  // namespace foresight
