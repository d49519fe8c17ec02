#pragma once
/// Navigation episodes in one harness (thesis ch 5, "Experimental Evaluation"): the crowd of the
/// scenario (simulated or replayed), a unicycle robot stepped at dt, and a controller per method
/// (SPAN, reactive, CL-RRT*, ORCA) fed each cycle with the last observed pedestrian positions.
/// Metrics (docs/navigation.md): success, time-to-goal (TTG, also censored at max_time), duration
/// of collision (DOC) and the part of it the robot causes, minimum clearance, control-cycle compute
/// time, and Wilson 95 % intervals on the rates. Writes DIR/episodes.csv, DIR/summary.json,
/// DIR/paths.png and DIR/episode.avi.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "datasets/crowd_scenario.h"
#include "inference/mapping/occupancy_map.h"
#include "inference/navigation/static_clearance.h"
#include "inference/prediction/span_predictor.h"
#include "training/navigation/config.h"
#include "training/run_dir.h"

namespace foresight::nav {

/// What every episode shares: the static map (through its artifact), the swept field, the
/// ground-truth obstacle raster (for collision metrics) and the predictor.
struct Resources {
  std::unique_ptr<occupancy::Map> map;
  std::unique_ptr<nav::StaticCollisionField> field;
  OccupancyRaster raster;
  Eigen::MatrixXf
      static_distance;  ///< [rows x cols] of `raster`: distance to the nearest obstacle (m)
  std::unique_ptr<span::Predictor> predictor;  ///< null when no method needs it
  double StaticDistance(double x, double y) const;
};

/// Builds DIR/map.h5 from the scenario (or loads map.artifact), and loads predictor.artifact when a
/// method needs it. Wrong artifact kinds, a start or goal in collision or an unreachable goal (no
/// free path on the static raster) are Errors naming the config key.
Resources PrepareNavigation(const ExperimentConfig& config, const std::string& out_dir);

struct EpisodeResult {
  std::string method;
  int episode = 0;
  std::uint64_t seed = 0;
  bool reached = false;
  double ttg = 0;         ///< s (time of arrival; max_time when not reached)
  double doc = 0;         ///< s in collision with a pedestrian or a static obstacle
  double doc_static = 0;  ///< s of `doc` in contact with a static obstacle
  /// s of `doc` with a robot-caused contact (RobotCausedContact; static contacts always are)
  double robot_caused_doc = 0;
  double min_clearance = 0;  ///< m, smallest gap to a pedestrian or obstacle (negative: overlap)
  double path_length = 0;    ///< m
  int cycles = 0, solve_failures = 0;
  /// Cycles whose chosen control collides within the horizon (a finite time-to-collision: no
  /// collision-free control was found); counted for controllers that report one (SPAN).
  int blocked_cycles = 0;
  int tau_cycles = 0;            ///< cycles whose controller reported a time-to-collision
  int fallback_cycles = 0;       ///< cycles whose command came from a fallback (SPAN's escape)
  double stopped_time = 0;       ///< s with a commanded speed below kRobotCausedSpeed
  double duration = 0;           ///< s simulated (cycles x dt)
  std::vector<double> cycle_ms;  ///< compute time of each control cycle
  Eigen::Matrix2Xd path;         ///< robot positions, one per cycle
};

/// Speed (m/s) above which the robot counts as moving, and as closing in on a pedestrian.
constexpr double kRobotCausedSpeed = 0.05;

/// Whether a robot-pedestrian contact at one step is the robot's fault (docs/navigation.md):
/// the discs overlap (distance < `radius_sum`), the pedestrian did not just appear inside the
/// robot's disc (`just_spawned`: it became active this step or the previous one while
/// overlapping), the robot moves (|robot_velocity| >= kRobotCausedSpeed) and its own velocity
/// toward the pedestrian, robot_velocity . n with n the unit vector robot -> pedestrian, exceeds
/// kRobotCausedSpeed. Coincident centres (no n) count as robot-caused when the robot moves.
/// @param robot_velocity [2] the robot's velocity over the step that ended at this contact (m/s)
bool RobotCausedContact(const Eigen::Vector2d& robot_position,
                        const Eigen::Vector2d& robot_velocity,
                        const Eigen::Vector2d& pedestrian_position, double radius_sum,
                        bool just_spawned);

/// Wilson score interval [lo, hi] of a binomial proportion k / n at normal quantile z (1.96:
/// 95 %): (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n), p = k / n. n = 0: [0, 1].
struct RateInterval {
  double lo = 0, hi = 1;
};
RateInterval WilsonInterval(int k, int n, double z = 1.96);

/// Draws frames of one episode (the video); null in RunEpisode for none.
class EpisodeRecorder {
 public:
  virtual ~EpisodeRecorder() = default;
  /// Called after each control cycle with the controller's predictions (SPAN; else empty).
  virtual void Frame(double time, const nav::UnicycleState& robot, const Eigen::Vector2d& goal,
                     const std::vector<CrowdAgent>& agents,
                     const std::vector<TrajectoryDistribution>* predictions, int num_predictions,
                     const Eigen::Matrix2Xd& path_so_far) = 0;
};

/// Runs one episode of `method` (span | reactive | cl_rrt_star | orca). Never throws from the
/// control loop.
EpisodeResult RunEpisode(const ExperimentConfig& config, const Resources& resources, Method method,
                         int episode, EpisodeRecorder* recorder = nullptr);

struct MethodSummary {
  std::string method;
  int episodes = 0;
  int successes = 0;                    ///< episodes that reached the goal
  int collision_free = 0;               ///< episodes with DOC = 0
  int success_and_collision_free = 0;   ///< reached and DOC = 0
  int robot_caused_collision_free = 0;  ///< episodes with robot-caused DOC = 0
  double success_rate = 0, collision_free_rate = 0;
  double success_and_collision_free_rate = 0, robot_caused_collision_free_rate = 0;
  /// Wilson 95 % intervals of the four rates above
  RateInterval success_rate_ci, collision_free_rate_ci, success_and_collision_free_rate_ci,
      robot_caused_collision_free_rate_ci;
  double ttg_mean = 0;           ///< over reached episodes (NaN -> null when none)
  double ttg_censored_mean = 0;  ///< over all episodes, a failure counting as its ttg (max_time)
  double doc_mean = 0;
  double robot_caused_doc_mean = 0;
  double min_clearance = 0;       ///< m, smallest gap over all episodes (negative: overlap)
  double min_clearance_mean = 0;  ///< m, mean over episodes of each episode's smallest gap
  double cycle_ms_median = 0, cycle_ms_p99 = 0, cycle_ms_max = 0;
  int solve_failures = 0;
  /// Share of all cycles that were blocked (EpisodeResult::blocked_cycles; NaN -> null for
  /// controllers that report no time-to-collision), and of the episodes' time spent stopped.
  double blocked_cycle_share = 0, stopped_time_share = 0;
  /// Share of all cycles whose command came from a fallback (ControlOutcome::fallback).
  double fallback_cycle_share = 0;
};
MethodSummary Summarise(const std::string& method, const std::vector<EpisodeResult>& results);

/// What shows a navigation run in a directory (episodes run in one pass: no resume).
inline const RunDirectoryRules kRunRules{{"summary.json", "episodes.csv"}, false};

/// Runs every method for `episodes` episodes (config.episodes when <= 0) into `out_dir`.
/// @return the summaries, in config.methods order.
std::vector<MethodSummary> RunNavigation(const ExperimentConfig& config, const std::string& out_dir,
                                         int episodes = 0);

/// summary.json text: {"scenario": ..., "episodes": N, "<method>": {...}, ...}.
std::string SummaryJson(const ExperimentConfig& config, int episodes,
                        const std::vector<MethodSummary>& s);

}  // namespace foresight::nav
