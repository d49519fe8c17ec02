#pragma once
/// A binary occupancy grid in cell units (thesis ch 6, Occ-Traj120): cell (row r, column c) covers
/// x in [c, c + 1), y in [r, r + 1), so occupied(x, y) = cells[floor(y)][floor(x)]
/// (../shared/data/occ_traj120/README.md: the convention under which every waypoint is free).
/// Trajectories on such grids are Eigen::MatrixX2d, one waypoint (x, y) per row, in cell units.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

namespace foresight {

struct BinaryGrid {
  int width = 0;                    ///< columns (x extent, cells)
  int height = 0;                   ///< rows (y extent, cells)
  std::vector<std::uint8_t> cells;  ///< row-major, cells[r * width + c]; 1 occupied, 0 free

  BinaryGrid() = default;
  BinaryGrid(int w, int h) : width(w), height(h), cells(static_cast<size_t>(w) * h, 0) {}

  bool Inside(int r, int c) const { return r >= 0 && r < height && c >= 0 && c < width; }
  std::uint8_t& at(int r, int c) { return cells[static_cast<size_t>(r) * width + c]; }
  std::uint8_t at(int r, int c) const { return cells[static_cast<size_t>(r) * width + c]; }
  /// cells[floor(y)][floor(x)]; a point outside the grid (or not finite) counts as occupied.
  bool OccupiedAt(double x, double y) const {
    if (!(x >= 0 && y >= 0 && x < width && y < height)) return true;
    return at(static_cast<int>(std::floor(y)), static_cast<int>(std::floor(x))) != 0;
  }
  int CountOccupied() const {
    int n = 0;
    for (std::uint8_t v : cells) n += v != 0;
    return n;
  }
};

}  // namespace foresight
