#pragma once
/// The data of a constrained-prediction run, computed deterministically from its config: the scenes
/// (tracks + obstacle raster), their split, and the observation/prediction windows of each split,
/// each window tagged with its scene (whose map scores it). Torch-free.

#include <string>
#include <vector>

#include "datasets/map_tracks.h"
#include "datasets/windows.h"
#include "training/constrained/config.h"

namespace foresight::constrained {

/// Windows of one split with the index of each window's scene in that split's scene list.
struct SceneWindows {
  WindowSet windows;
  std::vector<int> scene;  ///< [N] index into the split's scenes
};

struct ConstrainedData {
  MapTracksReport report;
  MapTracksSplit split;
  SceneWindows train, val, test;
};

/// Loads (or generates) the scenes, splits them and cuts the windows. No training, validation or
/// test windows is an Error naming the keys that control them.
ConstrainedData LoadConstrainedData(const ExperimentConfig& c);

/// Windows of every track of `scenes`, tagged with their scene.
SceneWindows MakeSceneWindows(const std::vector<MapScene>& scenes, const WindowConfig& windows);

/// The file name of a scene's fitted map inside the run directory: maps/<name>.h5 (the name made
/// safe for a file name).
std::string SceneMapFile(const MapScene& scene);

}  // namespace foresight::constrained
