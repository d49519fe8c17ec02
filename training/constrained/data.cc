#include "training/constrained/data.h"

#include <cctype>

#include "core/error.h"
#include "core/log.h"

namespace foresight::constrained {

SceneWindows MakeSceneWindows(const std::vector<MapScene>& scenes, const WindowConfig& windows) {
  std::vector<WindowSet> parts;
  SceneWindows out;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    WindowSet w = MakeWindows(scenes[s].tracks, windows);
    out.scene.insert(out.scene.end(), static_cast<std::size_t>(w.size()), static_cast<int>(s));
    parts.push_back(std::move(w));
  }
  if (parts.empty()) {
    out.windows.observed = windows.observed;
    out.windows.predicted = windows.predicted;
    out.windows.past.resize(0, 2 * windows.observed);
    out.windows.future.resize(0, 2 * windows.predicted);
    return out;
  }
  out.windows = Concat(parts);
  return out;
}

ConstrainedData LoadConstrainedData(const ExperimentConfig& c) {
  ConstrainedData d;
  const int length = c.windows.observed + c.windows.predicted;
  const std::vector<MapScene> scenes = LoadMapScenes(c.data, length, &d.report);
  d.split = SplitMapScenes(scenes, c.split.by_scene, c.split.val_fraction, c.split.test_fraction,
                           static_cast<std::uint64_t>(c.seed));
  d.train = MakeSceneWindows(d.split.train, c.windows);
  d.val = MakeSceneWindows(d.split.val, c.windows);
  d.test = MakeSceneWindows(d.split.test, c.windows);
  log::Info("constrained: ", d.report.scenes, " scenes, ", d.report.tracks_kept, " of ",
            d.report.tracks_read, " tracks kept (", d.report.too_short, " shorter than ", length,
            " points, ", d.report.outside_frame, " outside the map frame); ",
            d.report.points_in_obstacles, " samples of ", d.report.tracks_in_obstacles,
            " tracks on occupied cells; windows ", d.train.windows.size(), " train, ",
            d.val.windows.size(), " val, ", d.test.windows.size(), " test");
  const char* keys = c.split.by_scene
                         ? "(split.by_scene splits whole scenes: add scenes with data.scenes / "
                           "data.max_maps, or change split.val_fraction / split.test_fraction)"
                         : "(change split.val_fraction / split.test_fraction, or windows.observed "
                           "/ windows.predicted)";
  FS_THROW_UNLESS(d.train.windows.size() > 0, "constrained: no training windows of ", length,
                  " points ", keys);
  FS_THROW_UNLESS(d.val.windows.size() > 0, "constrained: no validation windows of ", length,
                  " points; the validation loss chooses the checkpoint ", keys);
  FS_THROW_UNLESS(d.test.windows.size() > 0, "constrained: no test windows of ", length, " points ",
                  keys);
  return d;
}

std::string SceneMapFile(const MapScene& scene) {
  std::string name = scene.name;
  for (char& ch : name)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-')) ch = '_';
  return "maps/" + name + ".h5";
}

}  // namespace foresight::constrained
