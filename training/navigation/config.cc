#include "training/navigation/config.h"

#include <algorithm>

#include "core/error.h"

namespace foresight::nav {

namespace {
constexpr Method kAllMethods[] = {Method::kSpan, Method::kReactive, Method::kClRrtStar,
                                  Method::kOrca};
}  // namespace

const char* MethodName(Method method) {
  switch (method) {
    case Method::kSpan:
      return "span";
    case Method::kReactive:
      return "reactive";
    case Method::kClRrtStar:
      return "cl_rrt_star";
    case Method::kOrca:
      return "orca";
  }
  return "";
}

Method ParseMethod(const std::string& name, const std::string& where) {
  for (const Method m : kAllMethods)
    if (name == MethodName(m)) return m;
  Fail(where, ": unknown method '", name, "' (expected span, reactive, cl_rrt_star or orca)");
}

std::vector<Method> ExperimentConfig::Methods() const {
  std::vector<Method> out;
  for (const std::string& m : methods) out.push_back(ParseMethod(m, "methods"));
  return out;
}

nav::OrcaControllerOptions MakeOrcaControllerOptions(const ExperimentConfig& c) {
  nav::OrcaControllerOptions o;
  o.time_horizon = c.orca.time_horizon;
  o.responsibility = c.orca.responsibility;
  o.heading_gain = c.orca.heading_gain;
  o.safety_margin = c.orca.safety_margin;
  o.dt = c.dt;
  o.robot_radius = c.scenario.robot_radius;
  o.pedestrian_radius = c.scenario.pedestrian_radius;
  o.epsilon = c.span.options.epsilon;
  o.limits = {-c.v_max, c.v_max, c.omega_max};
  return o;
}

bool ExperimentConfig::Uses(Method method) const {
  return std::find(methods.begin(), methods.end(), MethodName(method)) != methods.end();
}

void ExperimentConfig::Validate(const std::string& path) const {
  const ExperimentConfig& c = *this;
  FS_THROW_UNLESS(c.model == "navigation", path, ": model: '", c.model, "', expected 'navigation'");
  FS_THROW_UNLESS(!c.methods.empty(), path, ": methods: empty list");
  for (std::size_t i = 0; i < c.methods.size(); ++i) {
    const std::string& m = c.methods[i];
    (void)ParseMethod(m, path + ": methods");
    FS_THROW_UNLESS(std::find(c.methods.begin(), c.methods.begin() + static_cast<long>(i), m) ==
                        c.methods.begin() + static_cast<long>(i),
                    path, ": methods: '", m, "' listed twice");
  }
  nav::SpanControllerOptions o = c.span.options;
  o.dt = c.dt;
  const std::string span_problems = o.Problems();
  FS_THROW_UNLESS(span_problems.empty(), path, ": span: ", span_problems);
  const std::string rrt_problems = c.cl_rrt_star.options.Problems();
  FS_THROW_UNLESS(rrt_problems.empty(), path, ": cl_rrt_star: ", rrt_problems);
  const std::string orca_problems = MakeOrcaControllerOptions(c).Problems();
  FS_THROW_UNLESS(orca_problems.empty(), path, ": orca: ", orca_problems);
  FS_THROW_UNLESS(c.predictor.tracks == "scenario" || c.predictor.tracks == "replay", path,
                  ": predictor.tracks: '", c.predictor.tracks, "', expected scenario or replay");
  (void)ParseMethod(c.video.method, path + ": video.method");
  c.scenario.Validate(path + ": scenario");
  // Sizes the config implies, checked before anything is allocated: the rasters of the scenario's
  // extent (obstacle sampling and swept-occupancy field) and the recorded training crowd.
  const double width = c.scenario.extent[1] - c.scenario.extent[0];
  const double height = c.scenario.extent[3] - c.scenario.extent[2];
  const double finest = std::min(c.map.raster_resolution, c.map.field_resolution);
  const double cells = (width / finest + 1) * (height / finest + 1);
  constexpr double kMaxCells = 2.5e7;  // 100 MB of floats: a 250 m square at 5 cm
  FS_THROW_UNLESS(cells <= kMaxCells, path, ": scenario.extent ", width, " m x ", height, " m at ",
                  finest,
                  " m (the finer of map.raster_resolution and "
                  "map.field_resolution) needs ",
                  cells, " raster cells, more than ", kMaxCells,
                  "; shrink the extent or coarsen the resolution");
  if (c.predictor.tracks == "scenario") {
    const double steps = c.predictor.record_episodes * (c.predictor.record_duration / c.dt);
    constexpr double kMaxSteps = 2e6;
    FS_THROW_UNLESS(steps <= kMaxSteps, path, ": predictor.record_episodes ",
                    c.predictor.record_episodes, " x predictor.record_duration ",
                    c.predictor.record_duration, " s at dt ", c.dt, " s records ", steps,
                    " simulation steps, more than ", kMaxSteps);
  }
}

}  // namespace foresight::nav
