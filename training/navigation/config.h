#pragma once
/// The config of a navigation experiment (configs/navigation/*.yaml, `model: navigation`): the
/// crowd scenario, where the pedestrian predictor and the static map come from, the controllers
/// (SPAN and the reactive, CL-RRT* and ORCA baselines) and the episodes. Torch-free.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/crowd_scenario.h"
#include "inference/navigation/cl_rrt_star.h"
#include "inference/navigation/orca.h"
#include "inference/navigation/span_controller.h"

namespace foresight::nav {

/// The SPAN predictor used by the controller.
struct PredictorConfig {
  /// SPAN artifact (model.h5). When it does not exist, `foresight navigate` trains one there first
  /// (LibTorch builds): tracks from `tracks`, then the SPAN config `train_config` on them.
  std::string artifact = "runs/navigation_predictor/model.h5";
  std::string train_config =
      "default";  ///< "default": the embedded configs/navigation/predictor.yaml
  /// `key.path=value` overrides of train_config (a predictor variant without another file).
  std::vector<std::string> train_overrides;
  /// Training tracks: "scenario" records the simulated crowd of this config's scenario without the
  /// robot; "replay" reads `replay` (a recorded file other than the one navigated).
  std::string tracks = "scenario";
  int record_episodes = 12;     ///< scenario: seeded runs recorded
  double record_duration = 60;  ///< scenario: seconds per run
  /// Std of Gaussian noise added to recorded simulated positions (m): a tracker's measurement
  /// noise. Noise-free simulated tracks make the matrix-normal likelihood degenerate (near-zero
  /// residuals).
  double position_noise = 0.02;
  ReplayConfig replay;  ///< tracks: replay

  template <class A>
  void Serialize(A* a) {
    a->Visit("artifact", &artifact, config::Range::Any(),
             "SPAN artifact; trained there first when missing");
    a->Visit("train_config", &train_config, config::Range::Any(),
             "SPAN config used to train a missing artifact ('default': the embedded "
             "configs/navigation/predictor.yaml)");
    a->Visit("train_overrides", &train_overrides, config::Range::Any(),
             "key.path=value overrides of train_config (used only when the artifact is trained)");
    a->Visit("tracks", &tracks, config::Range::Any(), "training tracks: scenario | replay");
    a->Visit("record_episodes", &record_episodes, config::Range::Closed(1, 10000),
             "simulated runs recorded");
    // At most a day per run, like max_time; Validate bounds the total recorded steps.
    a->Visit("record_duration", &record_duration, config::Range::OpenClosed(0, 86400),
             "seconds per recorded run");
    a->Visit("position_noise", &position_noise, config::Range::NonNegative(),
             "std of measurement noise added to recorded simulated positions (m)");
    a->Visit("replay", &replay, config::Range::Any(), "recorded training tracks (tracks: replay)");
  }
};

enum class MapKind { kFastBhm, kGrid };

/// The static occupancy map: an artifact, or built from the scenario's obstacles.
struct MapConfig {
  std::string artifact;  ///< occupancy-map artifact; empty: build DIR/map.h5 from the scenario
  MapKind kind = MapKind::kFastBhm;
  double raster_resolution = 0.1;  ///< m, scenario obstacles sampled at this step (labelled points)
  double spacing = 0.25;  ///< m, Fast-BHM inducing-point spacing (gamma scales as spacing^-2)
  double field_resolution = 0.05;  ///< m, raster of the swept occupancy used by the controllers

  template <class A>
  void Serialize(A* a) {
    a->Visit("artifact", &artifact, config::Range::Any(),
             "occupancy-map artifact; empty: build from the scenario");
    a->VisitEnum(
        "kind", &kind,
        config::EnumNames<MapKind>{{MapKind::kFastBhm, "fast_bhm"}, {MapKind::kGrid, "grid"}},
        "map built from the scenario");
    a->Visit("raster_resolution", &raster_resolution, config::Range::Closed(0.01, 1.0),
             "sampling step of the scenario obstacles (m)");
    a->Visit("spacing", &spacing, config::Range::Closed(0.05, 2.0),
             "Fast-BHM inducing-point spacing (m)");
    a->Visit("field_resolution", &field_resolution, config::Range::Closed(0.01, 0.4),
             "resolution of the swept-occupancy raster (m)");
  }
};

struct SpanControllerConfig {
  nav::SpanControllerOptions options;
  template <class A>
  void Serialize(A* a) {
    auto& o = options;
    a->Visit("kappa", &o.kappa, config::Range::NonNegative(),
             "weight of the inverse time-to-collision");
    a->Visit("epsilon", &o.epsilon, config::Range::Open(0, 1), "chance threshold of a collision");
    a->Visit("horizon", &o.horizon, config::Range::Positive(), "look-ahead horizon T (s)");
    a->Visit("initialisations", &o.initialisations, config::Range::Closed(1, 100),
             "COBYLA starts per cycle");
    a->Visit("max_evaluations", &o.max_evaluations, config::Range::Closed(3, 10000),
             "COBYLA evaluations per start");
    a->Visit("xtol", &o.xtol, config::Range::Positive(), "COBYLA tolerance on the controls");
    a->Visit("initial_step", &o.initial_step, config::Range::Positive(),
             "COBYLA initial trust radius");
    a->Visit("geodesic_goal", &o.geodesic_goal, config::Range::Any(),
             "goal term as the distance around static obstacles (false: ||x(T) - g|| as printed)");
    a->Visit("escape_tau", &o.escape_tau, config::Range::NonNegative(),
             "fallback when the best plan collides within this many s: minimise the expected "
             "contacts over escape_horizon instead (0: off, the thesis)");
    a->Visit("escape_horizon", &o.escape_horizon, config::Range::Positive(),
             "window of the escape fallback (s), in [dt, horizon] when escape_tau > 0");
    a->Visit("commit_time", &o.commit_time, config::Range::NonNegative(),
             "commitment time t_c (s): collision tests beyond it hold the covariance at t_c "
             "(0: off, the thesis; else in [dt, horizon]; docs/navigation.md)");
    a->Visit("segments", &o.segments, config::Range::Closed(1, 8),
             "constant controls per horizon (1: the thesis's; 2: may change once, at T / 2)");
  }
};

struct ReactiveControllerConfig {
  double heading_weight = 0.5;  ///< m per rad of heading error in the one-step cost
  template <class A>
  void Serialize(A* a) {
    a->Visit("heading_weight", &heading_weight, config::Range::NonNegative(),
             "cost of heading error (m/rad)");
  }
};

struct ClRrtStarConfig {
  nav::ClRrtStarOptions options;
  template <class A>
  void Serialize(A* a) {
    auto& o = options;
    a->Visit("budget_s", &o.budget_s, config::Range::Positive(),
             "planning time budget per cycle (s)");
    a->Visit("max_iterations", &o.max_iterations, config::Range::AtLeast(1),
             "RRT* iterations per cycle");
    a->Visit("range", &o.range, config::Range::Positive(), "RRT* extension step (m)");
    a->Visit("goal_tolerance", &o.goal_tolerance, config::Range::Positive(),
             "planner goal radius (m)");
    a->Visit("lookahead", &o.lookahead, config::Range::Positive(), "pure-pursuit look-ahead (m)");
    a->Visit("check_resolution", &o.check_resolution, config::Range::Positive(),
             "edge checking step (m)");
    a->Visit("min_progress", &o.min_progress, config::Range::NonNegative(),
             "a partial plan is followed when it ends this much closer to the goal (m)");
  }
};

/// The ORCA baseline (inference/navigation/orca.h; van den Berg et al. 2011). The robot's radius,
/// dt, the control limits and the static threshold come from the experiment (epsilon: span's).
struct OrcaConfig {
  double time_horizon = 2.0;    ///< tau (s)
  double responsibility = 1.0;  ///< share of the avoidance the robot takes (0.5: reciprocal)
  double heading_gain = 2.0;    ///< 1/s
  double safety_margin = 0.1;   ///< m added to each pedestrian's radius
  template <class A>
  void Serialize(A* a) {
    a->Visit("time_horizon", &time_horizon, config::Range::Closed(0.1, 30),
             "ORCA time horizon tau: collisions later than this are ignored (s)");
    a->Visit("responsibility", &responsibility, config::Range::OpenClosed(0, 1),
             "share of the avoidance the robot takes per pedestrian (1: pedestrians do not react; "
             "0.5: reciprocal, as between ORCA agents)");
    a->Visit("heading_gain", &heading_gain, config::Range::Positive(),
             "turn rate per rad of heading error to the ORCA velocity (1/s), then clamped");
    a->Visit("safety_margin", &safety_margin, config::Range::Closed(0, 2),
             "added to each pedestrian's radius in ORCA (m)");
  }
};

/// The controllers a navigation experiment compares. Configs name them (`methods: [span, ...]`);
/// ParseMethod is the one place a name becomes a method.
enum class Method { kSpan, kReactive, kClRrtStar, kOrca };
const char* MethodName(Method method);
/// The method called `name`; an unknown name is an Error naming `where` and the known names.
Method ParseMethod(const std::string& name, const std::string& where);

struct VideoConfig {
  bool enabled = true;
  std::string method = "span";  ///< whose episode is filmed
  int episode = 0;
  int samples = 3;  ///< sampled predicted futures drawn per pedestrian
  double pixels_per_metre = 30;
  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &enabled, config::Range::Any(), "write DIR/episode.avi");
    a->Visit("method", &method, config::Range::Any(), "method of the filmed episode");
    a->Visit("episode", &episode, config::Range::AtLeast(0), "filmed episode");
    a->Visit("samples", &samples, config::Range::Closed(0, 20),
             "predicted futures drawn per pedestrian");
    a->Visit("pixels_per_metre", &pixels_per_metre, config::Range::Closed(5, 200), "video scale");
  }
};

struct ExperimentConfig {
  std::string model = "navigation";
  std::int64_t seed = 0;
  CrowdScenarioConfig scenario;
  PredictorConfig predictor;
  MapConfig map;
  std::vector<std::string> methods{"span", "reactive", "cl_rrt_star"};
  int episodes = 20;
  double max_time = 60;                 ///< s per episode
  double dt = 0.1;                      ///< s, control period and simulation step
  double goal_tolerance = 0.5;          ///< m
  double sensing_range = 10;            ///< m, pedestrians farther from the robot are not observed
  double v_max = 1.0, omega_max = 1.0;  ///< control limits (v in [-v_max, v_max])
  SpanControllerConfig span;
  ReactiveControllerConfig reactive;
  ClRrtStarConfig cl_rrt_star;
  OrcaConfig orca;
  VideoConfig video;

  template <class A>
  void Serialize(A* a) {
    a->Visit("model", &model, config::Range::Any(), "experiment type (navigation)");
    a->Visit("seed", &seed, config::Range::Any(), "seed of the episodes (episode i uses seed + i)");
    a->Visit("scenario", &scenario, config::Range::Any(), "crowd scenario");
    a->Visit("predictor", &predictor, config::Range::Any(), "SPAN pedestrian predictor");
    a->Visit("map", &map, config::Range::Any(), "static occupancy map");
    a->Visit("methods", &methods, config::Range::Any(),
             "controllers compared: span | reactive | cl_rrt_star | orca");
    a->Visit("episodes", &episodes, config::Range::Closed(1, 100000), "episodes per method");
    // At most a day: the cycle count max_time / dt must stay far inside an int.
    a->Visit("max_time", &max_time, config::Range::OpenClosed(0, 86400),
             "time limit of an episode (s)");
    a->Visit("dt", &dt, config::Range::Closed(0.01, 1.0), "control period and simulation step (s)");
    a->Visit("goal_tolerance", &goal_tolerance, config::Range::Positive(),
             "goal reached within this distance (m)");
    a->Visit("sensing_range", &sensing_range, config::Range::Positive(),
             "observation range of pedestrians (m)");
    a->Visit("v_max", &v_max, config::Range::Positive(), "linear velocity limit (m/s)");
    a->Visit("omega_max", &omega_max, config::Range::Positive(), "angular velocity limit (rad/s)");
    a->Visit("span", &span, config::Range::Any(), "SPAN controller");
    a->Visit("reactive", &reactive, config::Range::Any(), "reactive baseline");
    a->Visit("cl_rrt_star", &cl_rrt_star, config::Range::Any(), "CL-RRT* baseline");
    a->Visit("orca", &orca, config::Range::Any(), "ORCA baseline");
    a->Visit("video", &video, config::Range::Any(), "video of one episode");
  }
  /// Scenario and method checks; errors name `path` and the key.
  void Validate(const std::string& path) const;
  /// `methods` as methods (Validate has checked the names).
  std::vector<Method> Methods() const;
  bool Uses(Method method) const;
};

/// The ORCA controller's options of an experiment: the `orca` block with dt, the scenario's radii,
/// span.epsilon (static threshold) and the control limits.
nav::OrcaControllerOptions MakeOrcaControllerOptions(const ExperimentConfig& config);

}  // namespace foresight::nav
