#pragma once
/// OTNet's map encoding (thesis ch 6, "Encoding of Environmental Occupancy"; errata ch 6): a map is
/// the vector of its similarities to a database of representative maps,
///   phi_m = S_H(M, M_m) = exp(-delta_H(M, M_m)^2 / (2 l_H)),
///   delta_H(A, B) = (h(A, B) + h(B, A)) / 2,   h(A, B) = max_{a in A} min_{b in B} ||a - b||,
/// on the *edge points* of the occupied regions: occupied cells with at least one free 4-neighbour
/// inside the grid, as integer cell indices (col, row) (distances in cells). h(A, B) is read off a
/// distance transform of B's edge cells (OpenCV, exact Euclidean: DIST_L2 with DIST_MASK_PRECISE):
/// h(A, B) = max_{a in A} DT_B(a), linear in the pixels; tested against the brute-force definition.

#include <Eigen/Core>
#include <vector>

#include "core/binary_grid.h"

namespace foresight::otnet {

/// Edge cells of `map` as (col, row), in row-major order. Empty when nothing occupied touches a
/// free cell (an all-free or all-occupied map).
std::vector<Eigen::Vector2i> EdgeCells(const BinaryGrid& map);

/// The distance (cells, float) from every cell to the nearest of `edges`, row-major [height x
/// width], on a width x height grid; exact Euclidean (OpenCV). Error when `edges` is empty or an
/// edge lies outside the grid. `out` is resized to width * height (no allocation when sized).
void EdgeDistanceField(const std::vector<Eigen::Vector2i>& edges, int width, int height,
                       std::vector<float>* out);

/// h(A, B) = max_{a in A} field_B(a) for A's cells on field_B's grid (EdgeDistanceField of B).
double OneSidedHausdorff(const std::vector<Eigen::Vector2i>& a, const std::vector<float>& field_b,
                         int width);
/// The brute-force definition, O(|A| |B|) (for tests and as a reference). Error on an empty set.
double OneSidedHausdorffBruteForce(const std::vector<Eigen::Vector2i>& a,
                                   const std::vector<Eigen::Vector2i>& b);
/// delta_H(A, B) = (h(A, B) + h(B, A)) / 2 by brute force.
double AveragedHausdorffBruteForce(const std::vector<Eigen::Vector2i>& a,
                                   const std::vector<Eigen::Vector2i>& b);

/// S_H = exp(-d^2 / (2 l_H)) (l_H > 0, in squared cells as the thesis writes it).
inline double HausdorffSimilarity(double d, double length_scale) {
  return std::exp(-d * d / (2.0 * length_scale));
}

/// The database of representative maps and the encoder of new maps. Immutable after construction;
/// one Workspace per caller.
class MapEncoder {
 public:
  struct Workspace {
    std::vector<Eigen::Vector2i> edges;  ///< the query map's edge cells
    std::vector<float> field;            ///< its distance field
    std::vector<float> scratch;          ///< for the distance transform (sized once)
  };

  MapEncoder() = default;
  /// Precomputes every database map's edge cells and distance field. Error when the database is
  /// empty, the maps differ in size, a map has no edge cells (naming its index), or l_H <= 0.
  MapEncoder(std::vector<BinaryGrid> database, double length_scale);

  int size() const { return static_cast<int>(database_.size()); }
  int width() const { return width_; }
  int height() const { return height_; }
  double length_scale() const { return length_scale_; }
  const std::vector<BinaryGrid>& database() const { return database_; }

  Workspace MakeWorkspace() const;
  /// delta_H(map, database[m]) for every m into `distances` [size()]. Error when the map's size
  /// differs from the database's or it has no edge cells. Allocation-free once `ws` has been used
  /// for a map of this size (OpenCV's distance transform may allocate its own temporaries: see the
  /// alloc test).
  void Distances(const BinaryGrid& map, Workspace* ws, Eigen::Ref<Eigen::VectorXd> distances) const;
  /// phi = S_H(delta_H) into `phi` [size()].
  void Encode(const BinaryGrid& map, Workspace* ws, Eigen::Ref<Eigen::VectorXd> phi) const;
  /// Index of the nearest database map by delta_H (ties: the lowest index); the k-NN baseline.
  int Nearest(const BinaryGrid& map, Workspace* ws) const;

 private:
  std::vector<BinaryGrid> database_;
  std::vector<std::vector<Eigen::Vector2i>> edges_;
  std::vector<std::vector<float>> fields_;
  int width_ = 0, height_ = 0;
  double length_scale_ = 1;
};

}  // namespace foresight::otnet
