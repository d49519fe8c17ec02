#include "inference/otnet/map_encoding.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace foresight::otnet {
namespace {

void CheckGrid(const BinaryGrid& map, const char* what) {
  FS_THROW_UNLESS(map.width > 0 && map.height > 0, what, ": grid size must be positive, got ",
                  map.width, " x ", map.height);
  FS_THROW_UNLESS(map.cells.size() == static_cast<size_t>(map.width) * map.height, what,
                  ": grid has ", map.cells.size(), " cells, expected width * height = ",
                  static_cast<size_t>(map.width) * map.height);
}

/// Appends the edge cells of `map` to `out` after clearing it (no allocation within capacity).
void CollectEdges(const BinaryGrid& map, std::vector<Eigen::Vector2i>* out) {
  out->clear();
  for (int r = 0; r < map.height; ++r) {
    for (int c = 0; c < map.width; ++c) {
      if (map.at(r, c) == 0) continue;
      // A free 4-neighbour inside the grid makes an edge; the outside of the grid does not.
      const bool edge =
          (r > 0 && map.at(r - 1, c) == 0) || (r + 1 < map.height && map.at(r + 1, c) == 0) ||
          (c > 0 && map.at(r, c - 1) == 0) || (c + 1 < map.width && map.at(r, c + 1) == 0);
      if (edge) out->emplace_back(c, r);
    }
  }
}

/// Floats needed to hold a width x height 8-bit image.
size_t ScratchFloats(int width, int height) {
  return (static_cast<size_t>(width) * height + sizeof(float) - 1) / sizeof(float);
}

/// The exact Euclidean distance to the nearest edge (OpenCV measures the distance to the nearest
/// zero pixel, so edges are 0 and everything else 255). `scratch` holds the 8-bit source image and
/// `out` receives the field; both are wrapped in cv::Mat headers, so nothing is allocated per call
/// when they are sized (OpenCV's pool threads allocate their thread-local data once: alloc test).
void ComputeField(const std::vector<Eigen::Vector2i>& edges, int width, int height,
                  std::vector<float>* scratch, std::vector<float>* out) {
  FS_THROW_UNLESS(width > 0 && height > 0, "EdgeDistanceField: grid size must be positive, got ",
                  width, " x ", height);
  FS_THROW_UNLESS(!edges.empty(), "EdgeDistanceField: no edge cells (", width, " x ", height,
                  " grid): the distance to an empty set is undefined");
  for (size_t i = 0; i < edges.size(); ++i) {
    const Eigen::Vector2i& e = edges[i];
    FS_THROW_UNLESS(e.x() >= 0 && e.x() < width && e.y() >= 0 && e.y() < height,
                    "EdgeDistanceField: edge ", i, " (col ", e.x(), ", row ", e.y(),
                    ") is outside the ", width, " x ", height, " grid");
  }
  const size_t cells = static_cast<size_t>(width) * height;
  if (scratch->size() < ScratchFloats(width, height)) scratch->resize(ScratchFloats(width, height));
  out->resize(cells);
  // Byte access to float storage is allowed (char types may alias any object).
  auto* src_data = reinterpret_cast<unsigned char*>(scratch->data());
  std::fill(src_data, src_data + cells, static_cast<unsigned char>(255));
  for (const Eigen::Vector2i& e : edges) src_data[static_cast<size_t>(e.y()) * width + e.x()] = 0;
  const cv::Mat src(height, width, CV_8UC1, src_data);
  cv::Mat dst(height, width, CV_32FC1, out->data());
  cv::distanceTransform(src, dst, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  // create() inside OpenCV keeps our buffer when size and type match; check it was not replaced.
  FS_THROW_UNLESS(dst.data == reinterpret_cast<uchar*>(out->data()),
                  "EdgeDistanceField: OpenCV replaced the output buffer (", width, " x ", height,
                  "); the distance field would be stale");
}

/// h(A, B) read off B's field; A must be non-empty and inside the field's grid.
double FieldHausdorff(const std::vector<Eigen::Vector2i>& a, const std::vector<float>& field_b,
                      int width) {
  float worst = 0;
  for (const Eigen::Vector2i& p : a)
    worst = std::max(worst, field_b[static_cast<size_t>(p.y()) * width + p.x()]);
  return worst;
}

/// delta_H(A, B) = (h(A, B) + h(B, A)) / 2 (thesis ch 6), each one-sided term read off the other
/// set's distance field.
double FieldAveragedHausdorff(const std::vector<Eigen::Vector2i>& a,
                              const std::vector<float>& field_a,
                              const std::vector<Eigen::Vector2i>& b,
                              const std::vector<float>& field_b, int width) {
  return 0.5 * (FieldHausdorff(a, field_b, width) + FieldHausdorff(b, field_a, width));
}

}  // namespace

std::vector<Eigen::Vector2i> EdgeCells(const BinaryGrid& map) {
  CheckGrid(map, "EdgeCells");
  std::vector<Eigen::Vector2i> edges;
  CollectEdges(map, &edges);
  return edges;
}

void EdgeDistanceField(const std::vector<Eigen::Vector2i>& edges, int width, int height,
                       std::vector<float>* out) {
  FS_THROW_UNLESS(out != nullptr, "EdgeDistanceField: out is null");
  // The 8-bit source image is a temporary here; MapEncoder keeps it in its workspace instead.
  std::vector<float> scratch;
  ComputeField(edges, width, height, &scratch, out);
}

double OneSidedHausdorff(const std::vector<Eigen::Vector2i>& a, const std::vector<float>& field_b,
                         int width) {
  FS_THROW_UNLESS(width > 0, "OneSidedHausdorff: width must be positive, got ", width);
  FS_THROW_UNLESS(!field_b.empty() && field_b.size() % width == 0, "OneSidedHausdorff: field of ",
                  field_b.size(), " values is not a non-empty multiple of width ", width);
  FS_THROW_UNLESS(!a.empty(), "OneSidedHausdorff: the set A is empty");
  const int height = static_cast<int>(field_b.size() / width);
  for (size_t i = 0; i < a.size(); ++i)
    FS_THROW_UNLESS(a[i].x() >= 0 && a[i].x() < width && a[i].y() >= 0 && a[i].y() < height,
                    "OneSidedHausdorff: point ", i, " (col ", a[i].x(), ", row ", a[i].y(),
                    ") is outside the field's ", width, " x ", height, " grid");
  return FieldHausdorff(a, field_b, width);
}

double OneSidedHausdorffBruteForce(const std::vector<Eigen::Vector2i>& a,
                                   const std::vector<Eigen::Vector2i>& b) {
  FS_THROW_UNLESS(!a.empty(), "OneSidedHausdorffBruteForce: the set A is empty");
  FS_THROW_UNLESS(!b.empty(), "OneSidedHausdorffBruteForce: the set B is empty");
  double worst_sq = 0;
  for (const Eigen::Vector2i& p : a) {
    double best_sq = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2i& q : b)
      best_sq = std::min(best_sq, (p - q).cast<double>().squaredNorm());
    worst_sq = std::max(worst_sq, best_sq);
  }
  return std::sqrt(worst_sq);
}

double AveragedHausdorffBruteForce(const std::vector<Eigen::Vector2i>& a,
                                   const std::vector<Eigen::Vector2i>& b) {
  // delta_H(A, B) = (h(A, B) + h(B, A)) / 2 (thesis ch 6, symmetrised one-sided distance).
  return 0.5 * (OneSidedHausdorffBruteForce(a, b) + OneSidedHausdorffBruteForce(b, a));
}

MapEncoder::MapEncoder(std::vector<BinaryGrid> database, double length_scale)
    : database_(std::move(database)), length_scale_(length_scale) {
  FS_THROW_UNLESS(!database_.empty(), "MapEncoder: the map database is empty");
  FS_THROW_UNLESS(length_scale > 0 && std::isfinite(length_scale),
                  "MapEncoder: length scale l_H must be > 0 and finite, got ", length_scale);
  width_ = database_.front().width;
  height_ = database_.front().height;
  std::vector<float> scratch;
  edges_.resize(database_.size());
  fields_.resize(database_.size());
  for (size_t m = 0; m < database_.size(); ++m) {
    const BinaryGrid& map = database_[m];
    CheckGrid(map, "MapEncoder: database map");
    FS_THROW_UNLESS(map.width == width_ && map.height == height_, "MapEncoder: database map ", m,
                    " is ", map.width, " x ", map.height, ", map 0 is ", width_, " x ", height_);
    CollectEdges(map, &edges_[m]);
    FS_THROW_UNLESS(!edges_[m].empty(), "MapEncoder: database map ", m,
                    " has no edge cells (no occupied cell next to a free one)");
    ComputeField(edges_[m], width_, height_, &scratch, &fields_[m]);
  }
}

MapEncoder::Workspace MapEncoder::MakeWorkspace() const {
  Workspace ws;
  const size_t cells = static_cast<size_t>(width_) * height_;
  ws.edges.reserve(cells);
  ws.field.resize(cells);
  ws.scratch.resize(ScratchFloats(width_, height_));
  return ws;
}

namespace {

/// Edges and distance field of the query map into `ws`; checks it against the database's size.
void PrepareQuery(const BinaryGrid& map, int width, int height, int size,
                  MapEncoder::Workspace* ws) {
  FS_THROW_UNLESS(size > 0, "MapEncoder: the encoder has no database (default-constructed)");
  FS_THROW_UNLESS(ws != nullptr, "MapEncoder: workspace is null");
  FS_THROW_UNLESS(map.width == width && map.height == height, "MapEncoder: map is ", map.width,
                  " x ", map.height, ", the database's maps are ", width, " x ", height);
  CheckGrid(map, "MapEncoder: map");
  CollectEdges(map, &ws->edges);
  FS_THROW_UNLESS(!ws->edges.empty(),
                  "MapEncoder: map has no edge cells (no occupied cell next to a free one)");
  ComputeField(ws->edges, width, height, &ws->scratch, &ws->field);
}

}  // namespace

void MapEncoder::Distances(const BinaryGrid& map, Workspace* ws,
                           Eigen::Ref<Eigen::VectorXd> distances) const {
  FS_THROW_UNLESS(distances.size() == size(), "MapEncoder::Distances: output has ",
                  distances.size(), " entries, the database has ", size(), " maps");
  PrepareQuery(map, width_, height_, size(), ws);
  for (int m = 0; m < size(); ++m)
    distances[m] = FieldAveragedHausdorff(ws->edges, ws->field, edges_[m], fields_[m], width_);
}

void MapEncoder::Encode(const BinaryGrid& map, Workspace* ws,
                        Eigen::Ref<Eigen::VectorXd> phi) const {
  FS_THROW_UNLESS(phi.size() == size(), "MapEncoder::Encode: output has ", phi.size(),
                  " entries, the database has ", size(), " maps");
  Distances(map, ws, phi);
  // phi_m = S_H(M, M_m) = exp(-delta_H^2 / (2 l_H)) (thesis ch 6, the distance substitute kernel).
  for (Eigen::Index m = 0; m < phi.size(); ++m) phi[m] = HausdorffSimilarity(phi[m], length_scale_);
}

int MapEncoder::Nearest(const BinaryGrid& map, Workspace* ws) const {
  PrepareQuery(map, width_, height_, size(), ws);
  int best = 0;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int m = 0; m < size(); ++m) {
    const double d = FieldAveragedHausdorff(ws->edges, ws->field, edges_[m], fields_[m], width_);
    if (d < best_distance) {  // strict: ties keep the lowest index
      best_distance = d;
      best = m;
    }
  }
  return best;
}

}  // namespace foresight::otnet
