#pragma once
/// Transfer to a real map (thesis ch 6, "Transferring Trajectories in Simulated Environments to
/// Real-world Data", Fig. TransferEx): sections of an occupancy map from the occupancy pipeline
/// (e.g. the Intel lab) are rasterised to the training cell grid, encoded, and OTNet generates
/// start-conditioned trajectories on them; k-NN transfers the nearest training map's trajectories.

#include <string>

#include "inference/mapping/occupancy_map.h"
#include "inference/otnet/otnet_model.h"
#include "training/otnet/data.h"
#include "training/otnet/eval.h"

namespace foresight::otnet {

/// Section [x_min, y_min, side] (m) of `map` as a size x size grid: cell (r, c) is occupied when
/// p(occupied) at its centre (x_min + (c + 1/2) side / size, y_min + (r + 1/2) side / size) is at
/// or above threshold. Row r grows with y.
BinaryGrid RasteriseSection(const foresight::occupancy::Map& map, double x_min, double y_min,
                            double side, int size, double threshold);

/// Start points at the openings of the section's border (Occ-Traj120's trajectories enter through
/// a gap in the border wall): runs of free border cells, longest first, each run's middle cell
/// moved one cell inward; at most `count`. The grid's centre when the whole border is free.
std::vector<Eigen::Vector2d> BorderOpenings(const BinaryGrid& g, int count);

/// Generates on every configured section and start; figures transfer_* (acceptance rate, sections
/// without edges are an Error naming the section); draws plot_png when not empty.
Scores TransferToOccupancyMap(const ExperimentConfig& c, const OtnetModel& model,
                              const OtnetSplit& train, const std::string& plot_png);

}  // namespace foresight::otnet
