#include "training/navigation/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <queue>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "inference/mapping/grid_map.h"
#include "inference/navigation/cl_rrt_star.h"
#include "inference/navigation/goal_distance.h"
#include "inference/navigation/orca.h"
#include "inference/navigation/span_controller.h"
#include "models/occupancy/raster_map.h"
#include "training/navigation/render.h"

namespace foresight::nav {
namespace fs = std::filesystem;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool UsesPredictor(const ExperimentConfig& c) { return c.Uses(Method::kSpan); }

/// Fast-BHM (or grid) map of the scenario's obstacles, saved as an artifact at `path`.
void BuildScenarioMap(const ExperimentConfig& c, const OccupancyRaster& raster,
                      const std::string& path) {
  occupancy::RasterMapOptions o;
  o.kind = c.map.kind == MapKind::kGrid ? occupancy::RasterMapKind::kGrid
                                        : occupancy::RasterMapKind::kFastBhm;
  o.sample_step = c.map.raster_resolution;
  o.spacing = c.map.spacing;
  o.margin = 1.0;
  occupancy::WriteRasterMap(raster, o, path, config::ToYaml(c), c.seed);
}

/// Distance (m) from each raster cell to the nearest occupied cell or the outside of the raster
/// (outside the scene is occupied: a one-cell occupied border is added before the transform).
Eigen::MatrixXf DistanceToObstacles(const OccupancyRaster& r) {
  const int rows = static_cast<int>(r.cells.rows()), cols = static_cast<int>(r.cells.cols());
  cv::Mat free(rows + 2, cols + 2, CV_8U, cv::Scalar(0));
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) free.at<std::uint8_t>(i + 1, j + 1) = r.cells(i, j) ? 0 : 255;
  cv::Mat dist;
  cv::distanceTransform(free, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  Eigen::MatrixXf out(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      out(i, j) = dist.at<float>(i + 1, j + 1) * static_cast<float>(r.resolution);
  return out;
}

bool CellOf(const OccupancyRaster& r, double x, double y, int* row, int* col) {
  const double c = (x - r.extent[0]) / r.resolution, q = (r.extent[3] - y) / r.resolution;
  if (!(c >= 0 && q >= 0 && c < r.cells.cols() && q < r.cells.rows())) return false;
  *row = static_cast<int>(q);
  *col = static_cast<int>(c);
  return true;
}

/// Breadth-first search over raster cells with clearance > radius.
bool Reachable(const Resources& res, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
               double radius) {
  int r0, c0, r1, c1;
  if (!CellOf(res.raster, a.x(), a.y(), &r0, &c0) || !CellOf(res.raster, b.x(), b.y(), &r1, &c1))
    return false;
  const int rows = static_cast<int>(res.static_distance.rows()),
            cols = static_cast<int>(res.static_distance.cols());
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(rows) * cols, 0);
  std::queue<std::pair<int, int>> q;
  q.push({r0, c0});
  seen[static_cast<std::size_t>(r0) * cols + c0] = 1;
  while (!q.empty()) {
    const auto [r, c] = q.front();
    q.pop();
    if (r == r1 && c == c1) return true;
    for (const auto& [dr, dc] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const int nr = r + dr, nc = c + dc;
      if (nr < 0 || nc < 0 || nr >= rows || nc >= cols) continue;
      const std::size_t k = static_cast<std::size_t>(nr) * cols + nc;
      if (seen[k] || res.static_distance(nr, nc) <= radius) continue;
      seen[k] = 1;
      q.push({nr, nc});
    }
  }
  return false;
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

std::unique_ptr<nav::NavigationController> MakeController(const ExperimentConfig& c,
                                                          const Resources& res, Method method,
                                                          std::uint64_t seed) {
  nav::ControlLimits limits{-c.v_max, c.v_max, c.omega_max};
  nav::SpanControllerOptions o = c.span.options;
  o.dt = c.dt;
  o.robot_radius = c.scenario.robot_radius;
  o.pedestrian_radius = c.scenario.pedestrian_radius;
  o.limits = limits;
  switch (method) {
    case Method::kSpan:
      return std::make_unique<nav::SpanController>(res.predictor.get(), res.field.get(), o);
    case Method::kReactive:
      return std::make_unique<nav::ReactiveController>(res.field.get(), o,
                                                       c.reactive.heading_weight);
    case Method::kClRrtStar: {
      nav::ClRrtStarOptions r = c.cl_rrt_star.options;
      r.robot_radius = o.robot_radius;
      r.pedestrian_radius = o.pedestrian_radius;
      r.epsilon = o.epsilon;
      r.limits = limits;
      return std::make_unique<nav::ClRrtStarController>(res.field.get(), res.raster.extent, r,
                                                        seed);
    }
    case Method::kOrca:
      return std::make_unique<nav::OrcaController>(res.field.get(), MakeOrcaControllerOptions(c));
  }
  Fail("navigation: method ", static_cast<int>(method), " has no controller");
}

std::string Json(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

std::string Json(const RateInterval& i) { return "[" + Json(i.lo) + ", " + Json(i.hi) + "]"; }

}  // namespace

bool RobotCausedContact(const Eigen::Vector2d& robot_position,
                        const Eigen::Vector2d& robot_velocity,
                        const Eigen::Vector2d& pedestrian_position, double radius_sum,
                        bool just_spawned) {
  const Eigen::Vector2d d = pedestrian_position - robot_position;
  const double distance = d.norm();
  if (!(distance < radius_sum) || just_spawned) return false;
  if (robot_velocity.norm() < kRobotCausedSpeed) return false;  // standing still: run into
  if (distance <= 0) return true;
  return robot_velocity.dot(d / distance) > kRobotCausedSpeed;
}

RateInterval WilsonInterval(int k, int n, double z) {
  if (n <= 0) return {0.0, 1.0};
  const double nn = n, p = static_cast<double>(k) / nn, z2 = z * z;
  const double centre = (p + z2 / (2 * nn)) / (1 + z2 / nn);
  const double half = z * std::sqrt(p * (1 - p) / nn + z2 / (4 * nn * nn)) / (1 + z2 / nn);
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

double Resources::StaticDistance(double x, double y) const {
  int r, c;
  if (!CellOf(raster, x, y, &r, &c)) return 0.0;
  return static_distance(r, c);
}

Resources PrepareNavigation(const ExperimentConfig& c, const std::string& out_dir) {
  c.Validate("navigation config");  // configs built in code get the same checks as loaded ones
  Resources res;
  res.raster = ScenarioOccupancy(c.scenario, 0.05);
  res.static_distance = DistanceToObstacles(res.raster);
  std::string map_path = c.map.artifact;
  if (map_path.empty()) {
    map_path = out_dir + "/map.h5";
    BuildScenarioMap(c, res.raster, map_path);
  }
  res.map = occupancy::LoadMap(map_path);
  res.field = std::make_unique<nav::StaticCollisionField>(*res.map, c.scenario.robot_radius,
                                                          c.map.field_resolution);
  if (UsesPredictor(c)) {
    FS_THROW_UNLESS(fs::exists(c.predictor.artifact), "predictor.artifact: ", c.predictor.artifact,
                    " not found (train it with `foresight navigate` in a LibTorch build, or "
                    "`foresight train`)");
    res.predictor = std::make_unique<span::Predictor>(span::Predictor::Load(c.predictor.artifact));
    const double ratio = res.predictor->seconds_per_step() / c.dt;
    FS_THROW_UNLESS(std::abs(ratio - std::round(ratio)) < 1e-6 && ratio >= 1,
                    "predictor.artifact: ", c.predictor.artifact, " observes every ",
                    res.predictor->seconds_per_step(), " s, not a multiple of dt = ", c.dt, " s");
  }
  return res;
}

EpisodeResult RunEpisode(const ExperimentConfig& c, const Resources& res, Method method,
                         int episode, EpisodeRecorder* recorder) {
  EpisodeResult out;
  out.method = MethodName(method);
  out.episode = episode;
  out.seed = static_cast<std::uint64_t>(c.seed) + static_cast<std::uint64_t>(episode);
  std::unique_ptr<Crowd> crowd = MakeCrowd(c.scenario, out.seed);
  const EpisodeEndpoints ends = MakeEpisodeEndpoints(c.scenario, out.seed);
  std::unique_ptr<nav::NavigationController> controller = MakeController(c, res, method, out.seed);
  const nav::ControlLimits limits{-c.v_max, c.v_max, c.omega_max};

  // Observation window: p points every `stride` steps, the last one now.
  const int p = res.predictor ? res.predictor->observed() : 5;
  const int stride =
      res.predictor ? static_cast<int>(std::lround(res.predictor->seconds_per_step() / c.dt)) : 1;
  const std::size_t keep = static_cast<std::size_t>((p - 1) * stride + 1);
  std::unordered_map<std::int64_t, std::deque<Eigen::Vector2d>> history;
  auto observe = [&] {
    for (const CrowdAgent& a : crowd->agents()) {
      if (!a.active) {
        history.erase(a.id);
        continue;
      }
      auto& h = history[a.id];
      h.push_back(a.position);
      if (h.size() > keep) h.pop_front();
    }
  };
  observe();

  nav::UnicycleState s{ends.start[0], ends.start[1], ends.start[2]};
  const Eigen::Vector2d goal = ends.goal;
  const double r_robot = c.scenario.robot_radius;
  // When each active pedestrian appeared (step) and whether it appeared inside the robot's disc:
  // a contact with it within a step of that is never robot-caused.
  std::unordered_map<std::int64_t, std::pair<int, bool>> appeared;
  auto track = [&](int step) {
    for (const CrowdAgent& a : crowd->agents()) {
      if (!a.active) {
        appeared.erase(a.id);
        continue;
      }
      if (appeared.count(a.id) == 0)
        appeared[a.id] = {step, (a.position - s.position()).norm() < r_robot + a.radius};
    }
  };
  track(0);
  controller->Prepare(goal);  // per-goal set-up (distance field) outside the timed cycles
  const int max_cycles = static_cast<int>(std::ceil(c.max_time / c.dt));
  std::vector<Eigen::Vector2d> path{s.position()};
  Eigen::MatrixXd rows;
  auto clearance = [&] {
    double clear = res.StaticDistance(s.x, s.y) - r_robot;
    for (const CrowdAgent& a : crowd->agents())
      if (a.active)
        clear = std::min(clear, (a.position - s.position()).norm() - r_robot - a.radius);
    return clear;
  };
  double t = 0.0, min_clear = clearance();
  for (int cycle = 0; cycle < max_cycles; ++cycle) {
    if ((s.position() - goal).norm() <= c.goal_tolerance) {
      out.reached = true;
      break;
    }
    // Observed pedestrians within the sensing range.
    int n = 0;
    rows.resize(static_cast<Eigen::Index>(crowd->agents().size()), 2 * p);
    for (const CrowdAgent& a : crowd->agents()) {
      if (!a.active || (a.position - s.position()).norm() > c.sensing_range) continue;
      const auto& h = history.at(a.id);
      for (int i = 0; i < p; ++i) {
        const int back = (p - 1 - i) * stride;  // steps before now
        const int idx = std::max(0, static_cast<int>(h.size()) - 1 - back);
        rows.row(n).segment(2 * i, 2) = h[static_cast<std::size_t>(idx)].transpose();
      }
      ++n;
    }
    const Eigen::MatrixXd observed = rows.topRows(n);
    nav::NavigationInput in;
    in.robot = s;
    in.goal = goal;
    in.past_rows = &observed;
    in.observation_step = stride * c.dt;
    const auto t0 = std::chrono::steady_clock::now();
    nav::ControlOutcome u;
    try {
      u = controller->Compute(in);
    } catch (const std::exception& e) {  // controllers do not throw; count it if one ever does
      u = nav::ControlOutcome::Stop(nav::ControlStatus::kError, e.what());
    }
    out.cycle_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!u.solved()) {
      if (out.solve_failures == 0)
        log::Info(out.method, " episode ", episode, ": first unsolved cycle at t = ", t,
                  " s: ", nav::ToString(u.status), " (", u.message, ")");
      ++out.solve_failures;
    }
    if (!std::isnan(u.tau)) {
      ++out.tau_cycles;
      out.blocked_cycles += std::isfinite(u.tau);
    }
    out.fallback_cycles += u.fallback;
    const nav::Control cmd = limits.Clamp(u.command);
    if (std::abs(cmd.v) < kRobotCausedSpeed) out.stopped_time += c.dt;
    out.duration += c.dt;
    const nav::UnicycleState next = nav::EulerStep(s, cmd, c.dt);
    const Eigen::Vector2d robot_velocity = (next.position() - s.position()) / c.dt;
    RobotAgent robot;
    robot.position = next.position();
    robot.velocity = (next.position() - s.position()) / c.dt;
    robot.radius = r_robot;
    crowd->Step(c.dt, robot);
    out.path_length += (next.position() - s.position()).norm();
    s = next;
    t += c.dt;
    observe();
    path.push_back(s.position());
    ++out.cycles;
    track(cycle + 1);
    // Metrics at the new state.
    double clear = res.StaticDistance(s.x, s.y) - r_robot;
    bool robot_caused = clear < 0;  // the robot is the only mover near walls
    if (clear < 0) out.doc_static += c.dt;
    for (const CrowdAgent& a : crowd->agents())
      if (a.active) {
        clear = std::min(clear, (a.position - s.position()).norm() - r_robot - a.radius);
        const auto& [step, inside] = appeared.at(a.id);
        robot_caused =
            robot_caused || RobotCausedContact(s.position(), robot_velocity, a.position,
                                               r_robot + a.radius, inside && step >= cycle);
      }
    if (clear < 0) out.doc += c.dt;
    if (robot_caused) out.robot_caused_doc += c.dt;
    min_clear = std::min(min_clear, clear);
    if (recorder) try {
        Eigen::Matrix2Xd so_far(2, static_cast<Eigen::Index>(path.size()));
        for (std::size_t i = 0; i < path.size(); ++i)
          so_far.col(static_cast<Eigen::Index>(i)) = path[i];
        recorder->Frame(t, s, goal, crowd->agents(), controller->Predictions(),
                        controller->PredictedPedestrians(), so_far);
      } catch (const std::exception& e) {  // a video problem must not lose the episode
        log::Warn("video: ", e.what(), "; no more frames");
        recorder = nullptr;
      }
  }
  if (!out.reached && (s.position() - goal).norm() <= c.goal_tolerance) out.reached = true;
  out.ttg = out.reached ? t : c.max_time;
  out.min_clearance = min_clear;
  out.path.resize(2, static_cast<Eigen::Index>(path.size()));
  for (std::size_t i = 0; i < path.size(); ++i)
    out.path.col(static_cast<Eigen::Index>(i)) = path[i];
  return out;
}

MethodSummary Summarise(const std::string& method, const std::vector<EpisodeResult>& results) {
  MethodSummary m;
  m.method = method;
  std::vector<double> cycles, ttg;
  double doc = 0, robot_doc = 0, clear = 0, worst = kInf, ttg_censored = 0;
  double stopped = 0, elapsed = 0;
  int blocked = 0, tau_cycles = 0, fallback = 0, all_cycles = 0;
  for (const EpisodeResult& r : results) {
    if (r.method != method) continue;
    ++m.episodes;
    m.successes += r.reached;
    m.collision_free += r.doc == 0.0;
    m.success_and_collision_free += r.reached && r.doc == 0.0;
    m.robot_caused_collision_free += r.robot_caused_doc == 0.0;
    if (r.reached) ttg.push_back(r.ttg);
    ttg_censored += r.ttg;  // max_time for an episode that did not reach the goal
    doc += r.doc;
    robot_doc += r.robot_caused_doc;
    clear += r.min_clearance;
    worst = std::min(worst, r.min_clearance);
    m.solve_failures += r.solve_failures;
    blocked += r.blocked_cycles;
    tau_cycles += r.tau_cycles;
    fallback += r.fallback_cycles;
    all_cycles += r.cycles;
    stopped += r.stopped_time;
    elapsed += r.duration;
    cycles.insert(cycles.end(), r.cycle_ms.begin(), r.cycle_ms.end());
  }
  m.success_rate_ci = WilsonInterval(m.successes, m.episodes);
  m.collision_free_rate_ci = WilsonInterval(m.collision_free, m.episodes);
  m.success_and_collision_free_rate_ci = WilsonInterval(m.success_and_collision_free, m.episodes);
  m.robot_caused_collision_free_rate_ci = WilsonInterval(m.robot_caused_collision_free, m.episodes);
  if (m.episodes == 0) return m;
  const double n = m.episodes;
  m.success_rate = m.successes / n;
  m.collision_free_rate = m.collision_free / n;
  m.success_and_collision_free_rate = m.success_and_collision_free / n;
  m.robot_caused_collision_free_rate = m.robot_caused_collision_free / n;
  m.ttg_censored_mean = ttg_censored / n;
  m.robot_caused_doc_mean = robot_doc / n;
  m.ttg_mean = ttg.empty()
                   ? std::nan("")
                   : std::accumulate(ttg.begin(), ttg.end(), 0.0) / static_cast<double>(ttg.size());
  m.doc_mean = doc / m.episodes;
  m.min_clearance_mean = clear / m.episodes;
  m.min_clearance = worst;
  m.cycle_ms_median = Percentile(cycles, 0.5);
  m.cycle_ms_p99 = Percentile(cycles, 0.99);
  m.cycle_ms_max = cycles.empty() ? std::nan("") : *std::max_element(cycles.begin(), cycles.end());
  m.blocked_cycle_share = tau_cycles > 0 ? static_cast<double>(blocked) / tau_cycles : std::nan("");
  m.stopped_time_share = elapsed > 0 ? stopped / elapsed : std::nan("");
  m.fallback_cycle_share =
      all_cycles > 0 ? static_cast<double>(fallback) / all_cycles : std::nan("");
  return m;
}

std::string SummaryJson(const ExperimentConfig& c, int episodes,
                        const std::vector<MethodSummary>& s) {
  std::ostringstream j;
  std::string name;
  for (char ch : c.scenario.name) {
    if (ch == '"' || ch == '\\') name += '\\';
    if (static_cast<unsigned char>(ch) >= 0x20) name += ch;
  }
  j << "{\n  \"scenario\": \"" << name << "\",\n  \"episodes\": " << episodes
    << ",\n  \"seed\": " << c.seed;
  for (const MethodSummary& m : s) {
    j << ",\n  \"" << m.method << "\": {\"success_rate\": " << Json(m.success_rate)
      << ", \"collision_free_rate\": " << Json(m.collision_free_rate)
      << ", \"ttg_mean\": " << Json(m.ttg_mean) << ", \"doc_mean\": " << Json(m.doc_mean)
      << ", \"min_clearance\": " << Json(m.min_clearance)
      << ", \"min_clearance_mean\": " << Json(m.min_clearance_mean)
      << ", \"cycle_ms_median\": " << Json(m.cycle_ms_median)
      << ", \"cycle_ms_p99\": " << Json(m.cycle_ms_p99)
      << ", \"cycle_ms_max\": " << Json(m.cycle_ms_max)
      << ", \"blocked_cycle_share\": " << Json(m.blocked_cycle_share)
      << ", \"stopped_time_share\": " << Json(m.stopped_time_share)
      << ", \"fallback_cycle_share\": " << Json(m.fallback_cycle_share)
      << ", \"solve_failures\": " << m.solve_failures << ", \"episodes\": " << m.episodes
      << ", \"successes\": " << m.successes << ", \"collision_free\": " << m.collision_free
      << ", \"success_and_collision_free\": " << m.success_and_collision_free
      << ", \"success_and_collision_free_rate\": " << Json(m.success_and_collision_free_rate)
      << ", \"robot_caused_collision_free\": " << m.robot_caused_collision_free
      << ", \"robot_caused_collision_free_rate\": " << Json(m.robot_caused_collision_free_rate)
      << ", \"ttg_censored_mean\": " << Json(m.ttg_censored_mean)
      << ", \"robot_caused_doc_mean\": " << Json(m.robot_caused_doc_mean)
      << ", \"success_rate_ci\": " << Json(m.success_rate_ci)
      << ", \"collision_free_rate_ci\": " << Json(m.collision_free_rate_ci)
      << ", \"success_and_collision_free_rate_ci\": " << Json(m.success_and_collision_free_rate_ci)
      << ", \"robot_caused_collision_free_rate_ci\": "
      << Json(m.robot_caused_collision_free_rate_ci) << "}";
  }
  j << "\n}\n";
  return j.str();
}

std::vector<MethodSummary> RunNavigation(const ExperimentConfig& c, const std::string& out_dir,
                                         int episodes) {
  fs::create_directories(out_dir);
  const int n = episodes > 0 ? episodes : c.episodes;
  const Resources res = PrepareNavigation(c, out_dir);
  // Every episode's start and goal must be free and connected on the static map.
  for (int e = 0; e < n; ++e) {
    const EpisodeEndpoints ends =
        MakeEpisodeEndpoints(c.scenario, static_cast<std::uint64_t>(c.seed) + e);
    const Eigen::Vector2d start(ends.start[0], ends.start[1]);
    const double r = c.scenario.robot_radius;
    FS_THROW_UNLESS(res.StaticDistance(start.x(), start.y()) > r, "scenario.robot_start: (",
                    start.transpose(), ") of episode ", e,
                    " is in collision with a static obstacle");
    FS_THROW_UNLESS(res.StaticDistance(ends.goal.x(), ends.goal.y()) > r, "scenario.robot_goal: (",
                    ends.goal.transpose(), ") of episode ", e,
                    " is inside or too close to a static obstacle");
    FS_THROW_UNLESS(Reachable(res, start, ends.goal, r), "scenario.robot_goal: (",
                    ends.goal.transpose(), ") of episode ", e,
                    " is unreachable from the start on the static map");
    // The controllers see the map artifact (through the swept field), not the raster: check there
    // too.
    occupancy::MapWorkspace ws = res.field->MakeWorkspace();
    const double eps = c.span.options.epsilon;
    FS_THROW_UNLESS(!res.field->Collides(start.x(), start.y(), eps, &ws), "scenario.robot_start: (",
                    start.transpose(), ") of episode ", e,
                    " is in collision on the map artifact (swept occupancy above epsilon ", eps,
                    ")");
    FS_THROW_UNLESS(!res.field->Collides(ends.goal.x(), ends.goal.y(), eps, &ws),
                    "scenario.robot_goal: (", ends.goal.transpose(), ") of episode ", e,
                    " is occupied on the map artifact");
    FS_THROW_UNLESS(nav::GoalDistanceField(*res.field, ends.goal, eps).Reaches(start),
                    "scenario.robot_goal: (", ends.goal.transpose(), ") of episode ", e,
                    " is unreachable from the start on the map artifact");
  }
  std::vector<EpisodeResult> results;
  // Rewritten (atomically) after every episode: a stopped run keeps the episodes it finished.
  std::ostringstream csv;
  csv << "method,episode,seed,reached,ttg,doc,doc_static,min_clearance,path_length,cycles,solve_"
         "failures,cycle_ms_median,cycle_ms_p99,robot_caused_doc,blocked_cycles,stopped_time,"
         "fallback_cycles\n";
  for (const Method method : c.Methods()) {
    for (int e = 0; e < n; ++e) {
      std::unique_ptr<VideoRecorder> video;
      if (c.video.enabled && MethodName(method) == c.video.method && e == c.video.episode)
        video = std::make_unique<VideoRecorder>(out_dir + "/episode.avi", res.raster, c.video, c.dt,
                                                c.seed);
      EpisodeResult r = RunEpisode(c, res, method, e, video.get());
      csv << r.method << ',' << r.episode << ',' << r.seed << ',' << r.reached << ',' << r.ttg
          << ',' << r.doc << ',' << r.doc_static << ',' << r.min_clearance << ',' << r.path_length
          << ',' << r.cycles << ',' << r.solve_failures << ',' << Percentile(r.cycle_ms, 0.5) << ','
          << Percentile(r.cycle_ms, 0.99) << ',' << r.robot_caused_doc << ','
          << (r.tau_cycles > 0 ? std::to_string(r.blocked_cycles) : std::string()) << ','
          << r.stopped_time << ',' << r.fallback_cycles << '\n';
      WriteFileAtomically(out_dir + "/episodes.csv", csv.str());
      log::Info(r.method, " episode ", e, ": ", r.reached ? "reached" : "not reached", " ttg ",
                r.ttg, " s, doc ", r.doc, " s, min clearance ", r.min_clearance,
                " m, cycle median ", Percentile(r.cycle_ms, 0.5), " ms");
      results.push_back(std::move(r));
    }
  }
  std::vector<MethodSummary> summaries;
  for (const std::string& method : c.methods) summaries.push_back(Summarise(method, results));
  WriteFileAtomically(out_dir + "/summary.json", SummaryJson(c, n, summaries));
  DrawPaths(out_dir + "/paths.png", res.raster, c, results);
  return summaries;
}

}  // namespace foresight::nav
