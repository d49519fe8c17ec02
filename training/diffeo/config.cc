#include "training/diffeo/config.h"

#include <set>

#include "core/error.h"

namespace foresight::imitation {

void ExperimentConfig::Validate(const std::string& source) const {
  FS_THROW_UNLESS(model == "diffeo", source, ": model: '", model, "', expected 'diffeo'");
  FS_THROW_UNLESS(!data.shapes.empty(), source, ": data.shapes: empty list (name shapes or [all])");
  FS_THROW_UNLESS(data.task == "push_box" || data.task == "lift_box", source, ": data.task: '",
                  data.task, "', expected push_box or lift_box");
  std::set<int> held;
  for (int i : data.held_out) {
    FS_THROW_UNLESS(i >= 0, source, ": data.held_out: ", i, " is negative");
    FS_THROW_UNLESS(held.insert(i).second, source, ": data.held_out: ", i, " listed twice");
  }
  std::set<int> excluded;
  for (int i : data.excluded) {
    FS_THROW_UNLESS(i >= 0, source, ": data.excluded: ", i, " is negative");
    FS_THROW_UNLESS(excluded.insert(i).second, source, ": data.excluded: ", i, " listed twice");
    FS_THROW_UNLESS(held.count(i) == 0, source, ": demo ", i,
                    " is in both data.held_out and data.excluded");
  }
  const auto check_list = [&](const std::vector<double>& v, const char* key) {
    FS_THROW_UNLESS(!v.empty(), source, ": ", key, ": empty list");
    for (std::size_t i = 0; i < v.size(); ++i) {
      FS_THROW_UNLESS(v[i] > 0 && v[i] < 1e6, source, ": ", key, "[", i, "]: ", v[i],
                      " is outside (0, 1e6)");
      FS_THROW_UNLESS(i == 0 || v[i] > v[i - 1], source, ": ", key, ": not increasing at [", i,
                      "]");
    }
  };
  if (obstacle.enabled) {
    check_list(obstacle.times, "obstacle.times");
    if (eflow.enabled) check_list(obstacle.repulsor_gains, "obstacle.repulsor_gains");
    FS_THROW_UNLESS(obstacle.sample_spacing < obstacle.radius, source,
                    ": obstacle.sample_spacing (", obstacle.sample_spacing,
                    ") must be below obstacle.radius (", obstacle.radius, ") to sample it");
  }
  FS_THROW_UNLESS(flow.cutoff_radius >= flow.spacing, source, ": flow.cutoff_radius (",
                  flow.cutoff_radius, ") is below flow.spacing (", flow.spacing,
                  "): most states would have no feature");
  FS_THROW_UNLESS(flow.segments <= flow.steps, source, ": flow.segments (", flow.segments,
                  ") exceeds flow.steps (", flow.steps, "): each segment needs an Euler step");
  for (std::size_t i = 0; i < flow.alternatives.size(); ++i)
    FS_THROW_UNLESS(flow.segments <= flow.alternatives[i].steps, source, ": flow.segments (",
                    flow.segments, ") exceeds flow.alternatives[", i, "].steps (",
                    flow.alternatives[i].steps, "): each segment needs an Euler step");
  FS_THROW_UNLESS(flow.TotalRestarts() <= 1000, source, ": flow.restarts x (1 + ",
                  "flow.alternatives) = ", flow.TotalRestarts(), " flows per shape; at most 1000");
  if (bias.enabled) {
    const std::size_t d = data.source == DemoSource::kTaskSpace ? 3 : 2;
    FS_THROW_UNLESS(bias.target.size() == d, source, ": bias.target: ", bias.target.size(),
                    " numbers, expected ", d, " (the demonstrations' dimension)");
  }
}

}  // namespace foresight::imitation
