#include "training/navigation_config.h"

#include <algorithm>

#include "core/error.h"

namespace foresight {

namespace {
NavigationExperimentConfig Checked(NavigationExperimentConfig c, const std::string& path) {
  FS_THROW_UNLESS(c.model == "navigation", path, ": model: '", c.model, "', expected 'navigation'");
  FS_THROW_UNLESS(!c.methods.empty(), path, ": methods: empty list");
  for (std::size_t i = 0; i < c.methods.size(); ++i) {
    const std::string& m = c.methods[i];
    FS_THROW_UNLESS(m == "span" || m == "reactive" || m == "cl_rrt_star", path, ": methods: unknown method '", m,
                    "' (expected span, reactive or cl_rrt_star)");
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
  FS_THROW_UNLESS(c.predictor.tracks == "scenario" || c.predictor.tracks == "replay", path,
                  ": predictor.tracks: '", c.predictor.tracks, "', expected scenario or replay");
  c.scenario.Validate(path + ": scenario");
  return c;
}
}  // namespace

NavigationExperimentConfig LoadNavigationConfig(const std::string& path, const std::vector<std::string>& overrides) {
  return Checked(config::LoadFile<NavigationExperimentConfig>(path, overrides), path);
}

NavigationExperimentConfig NavigationConfigFromYaml(const std::string& yaml_text, const std::string& source,
                                                    const std::vector<std::string>& overrides) {
  return Checked(config::FromYaml<NavigationExperimentConfig>(config::ParseYaml(yaml_text, source), source, overrides),
                 source);
}

}  // namespace foresight
