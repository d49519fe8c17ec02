#include "training/navigation_config.h"

#include "core/error.h"

namespace foresight {

namespace {
NavigationExperimentConfig Checked(NavigationExperimentConfig c, const std::string& path) {
  FS_THROW_UNLESS(c.model == "navigation", path, ": model: '", c.model, "', expected 'navigation'");
  FS_THROW_UNLESS(!c.methods.empty(), path, ": methods: empty list");
  for (const std::string& m : c.methods)
    FS_THROW_UNLESS(m == "span" || m == "reactive" || m == "cl_rrt_star", path, ": methods: unknown method '", m,
                    "' (expected span, reactive or cl_rrt_star)");
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
