#pragma once
/// Occupancy grid by log-odds updates along each beam (the grid baseline of thesis ch 3): cells
/// traversed by a beam get l_free, the cell of its end point l_occupied, clamped to
/// [l_min, l_max]; within one scan a cell is updated once and "occupied" wins (as OctoMap does).
/// Beams without a valid return (range <= 0, non-finite or >= max_range) are skipped, matching
/// the labelled-point sampler. Defaults are OctoMap's sensor model (hit 0.7, miss 0.4, clamping
/// 0.12 / 0.97).

#include <vector>

#include "core/config.h"
#include "datasets/laser_scan.h"
#include "inference/mapping/grid_map.h"

namespace foresight::occupancy {

struct GridMapConfig {
  double x_min = -20, x_max = 20, y_min = -25, y_max = 10;  ///< m, extent of the grid
  double resolution = 0.1;                                  ///< m per cell
  double max_range = 40.0;                                  ///< m, longer beams are skipped
  double p_hit = 0.7, p_miss = 0.4;                         ///< inverse sensor model
  double p_min = 0.12, p_max = 0.97;                        ///< clamping
  CellType cell_type = CellType::kFloat32;

  template <class A>
  void Serialize(A* a) {
    a->Visit("x_min", &x_min, config::Range::Any(), "grid extent (m)");
    a->Visit("x_max", &x_max, config::Range::Any(), "grid extent (m)");
    a->Visit("y_min", &y_min, config::Range::Any(), "grid extent (m)");
    a->Visit("y_max", &y_max, config::Range::Any(), "grid extent (m)");
    a->Visit("resolution", &resolution, config::Range::Positive(), "cell side (m)");
    a->Visit("max_range", &max_range, config::Range::Positive(),
             "beams at or beyond this range are skipped (m)");
    a->Visit("p_hit", &p_hit, config::Range::Open(0.5, 1),
             "occupancy probability of an end-point cell");
    a->Visit("p_miss", &p_miss, config::Range::Open(0, 0.5),
             "occupancy probability of a traversed cell");
    a->Visit("p_min", &p_min, config::Range::Open(0, 0.5), "lower clamp of a cell's probability");
    a->Visit("p_max", &p_max, config::Range::Open(0.5, 1), "upper clamp of a cell's probability");
    a->VisitEnum(
        "cell_type", &cell_type,
        config::EnumNames<CellType>{{CellType::kFloat32, "float32"}, {CellType::kUint8, "uint8"}},
        "stored cell type");
  }
};

/// Builds the grid by inserting the scans in order.
GridMap BuildGridMap(const GridMapConfig& config, const std::vector<LaserScan>& scans);

/// Cells visited by the segment from (x0, y0) to (x1, y1) in grid coordinates (cell units),
/// in order, ending with the cell of the end point (Amanatides-Woo traversal).
void TraverseCells(double x0, double y0, double x1, double y1,
                   std::vector<std::pair<int, int>>* cells);

}  // namespace foresight::occupancy
