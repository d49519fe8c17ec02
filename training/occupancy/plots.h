#pragma once
/// PNG figures of occupancy maps (OpenCV): per map a probability panel (white free, black
/// occupied) above a panel of log10 latent variance (Bayesian maps).

#include <string>
#include <vector>

#include "inference/mapping/occupancy_map.h"

namespace foresight::occupancy {

struct MapPanel {
  std::string title;
  const Map* map;
};

/// Renders every map over the first map's extent at `resolution` m per pixel, side by side.
void WriteMapPanels(const std::vector<MapPanel>& panels, double resolution,
                    const std::string& png_path);

}  // namespace foresight::occupancy
