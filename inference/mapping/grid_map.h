#pragma once
/// Occupancy grid (the baseline of thesis ch 3): a probability per square cell, stored in the
/// artifact as float32 or as one byte per cell (0..254 -> p = q / 254, 255 = unknown), like the
/// compact grids of ROS. Queries read the cell under the point (a grid is piecewise constant); the
/// gradient is the central difference of the neighbouring cells; variance is 0. Points outside the
/// grid and unknown cells answer p = 0.5.
///
/// Artifact: /model attrs {x_min, y_min, resolution, nx, ny, cell_type}, /cells [ny x nx]
/// (float32 or uint8; see docs/artifact_schema.md).

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "core/config.h"
#include "inference/mapping/occupancy_map.h"

namespace foresight::occupancy {

enum class CellType { kFloat32, kUint8 };

struct GridGeometry {
  double x_min = -20, y_min = -25;  ///< m, corner of cell (0, 0)
  double resolution = 0.1;          ///< m, cell side
  int nx = 400, ny = 350;           ///< cells along x and y
  /// Cell of a point, or false when outside.
  bool Cell(double x, double y, int* ix, int* iy) const {
    const double fx = (x - x_min) / resolution, fy = (y - y_min) / resolution;
    if (!(fx >= 0 && fy >= 0 && fx < nx && fy < ny)) return false;
    *ix = static_cast<int>(fx);
    *iy = static_cast<int>(fy);
    return true;
  }
};

class GridMap final : public Map {
 public:
  /// @param probability [ny x nx] p(occupied) per cell in [0, 1], NaN = unknown.
  GridMap(GridGeometry geometry, Eigen::MatrixXf probability, CellType cell_type);
  static GridMap Load(const std::string& path);
  void Save(const std::string& path, const std::string& config_yaml, std::int64_t seed) const;

  const GridGeometry& geometry() const { return geometry_; }
  CellType cell_type() const { return cell_type_; }
  /// Cell probabilities as stored (after one-byte quantisation for kUint8); unknown = NaN.
  const Eigen::MatrixXf& cells() const { return cells_; }
  /// Bytes of the cell payload (nx * ny * 4 or nx * ny).
  std::int64_t PayloadBytes() const;

  std::string model_type() const override { return kGridMapType; }
  MapWorkspace MakeWorkspace() const override { return {}; }
  QueryResult Query(double x, double y, MapWorkspace* ws) const override;
  double Probability(double x, double y, MapWorkspace* ws) const override;
  Eigen::Vector4d Extent() const override;

 private:
  double CellOrHalf(int ix, int iy) const;
  GridGeometry geometry_;
  Eigen::MatrixXf cells_;
  CellType cell_type_;
};

/// One-byte code of a probability (NaN -> 255 unknown) and back.
std::uint8_t EncodeCell(float p);
float DecodeCell(std::uint8_t q);

}  // namespace foresight::occupancy
