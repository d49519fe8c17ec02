#include "inference/mapping/grid_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight::occupancy {

std::uint8_t EncodeCell(float p) {
  if (!std::isfinite(p)) return 255;
  return static_cast<std::uint8_t>(std::lround(std::clamp(p, 0.0f, 1.0f) * 254.0f));
}
float DecodeCell(std::uint8_t q) { return q == 255 ? 0.5f : static_cast<float>(q) / 254.0f; }

GridMap::GridMap(GridGeometry geometry, Eigen::MatrixXf probability, CellType cell_type)
    : geometry_(geometry), cells_(std::move(probability)), cell_type_(cell_type) {
  FS_THROW_UNLESS(geometry_.nx > 0 && geometry_.ny > 0 && geometry_.resolution > 0 &&
                      std::isfinite(geometry_.x_min) && std::isfinite(geometry_.y_min),
                  "grid map: invalid geometry ", geometry_.nx, " x ", geometry_.ny, " cells of ",
                  geometry_.resolution, " m");
  FS_THROW_UNLESS(cells_.rows() == geometry_.ny && cells_.cols() == geometry_.nx,
                  "grid map: cells are ", cells_.rows(), " x ", cells_.cols(), ", expected ",
                  geometry_.ny, " x ", geometry_.nx);
  for (Eigen::Index i = 0; i < cells_.size(); ++i) {
    float& p = cells_.data()[i];
    if (std::isnan(p)) continue;  // unknown: kept as NaN (stored as NaN / 255), answered as 0.5
    FS_THROW_UNLESS(p >= 0.0f && p <= 1.0f, "grid map: cell probability ", p, " outside [0, 1]");
    if (cell_type_ == CellType::kUint8) p = static_cast<float>(EncodeCell(p)) / 254.0f;
  }
}

std::int64_t GridMap::PayloadBytes() const {
  return static_cast<std::int64_t>(cells_.size()) * (cell_type_ == CellType::kUint8 ? 1 : 4);
}

double GridMap::CellOrHalf(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= geometry_.nx || iy >= geometry_.ny) return 0.5;
  const float p = cells_(iy, ix);
  return std::isnan(p) ? 0.5 : p;
}

double GridMap::Probability(double x, double y, MapWorkspace*) const {
  int ix, iy;
  if (!geometry_.Cell(x, y, &ix, &iy)) return 0.5;
  return CellOrHalf(ix, iy);
}

QueryResult GridMap::Query(double x, double y, MapWorkspace*) const {
  QueryResult q;
  int ix, iy;
  if (!geometry_.Cell(x, y, &ix, &iy)) return q;
  q.probability = CellOrHalf(ix, iy);
  const double h2 = 2.0 * geometry_.resolution;
  q.dp_dx = (CellOrHalf(ix + 1, iy) - CellOrHalf(ix - 1, iy)) / h2;
  q.dp_dy = (CellOrHalf(ix, iy + 1) - CellOrHalf(ix, iy - 1)) / h2;
  return q;
}

Eigen::Vector4d GridMap::Extent() const {
  const auto& g = geometry_;
  return {g.x_min, g.x_min + g.nx * g.resolution, g.y_min, g.y_min + g.ny * g.resolution};
}

void GridMap::Save(const std::string& path, const std::string& config_yaml,
                   std::int64_t seed) const {
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, kGridMapType, config_yaml, seed);
    f->SetAttr("/model", "x_min", geometry_.x_min);
    f->SetAttr("/model", "y_min", geometry_.y_min);
    f->SetAttr("/model", "resolution", geometry_.resolution);
    f->SetAttr("/model", "nx", static_cast<std::int64_t>(geometry_.nx));
    f->SetAttr("/model", "ny", static_cast<std::int64_t>(geometry_.ny));
    const std::vector<std::size_t> shape{static_cast<std::size_t>(geometry_.ny),
                                         static_cast<std::size_t>(geometry_.nx)};
    // Row-major [ny x nx]: row iy holds cells (0..nx-1, iy).
    if (cell_type_ == CellType::kUint8) {
      f->SetAttr("/model", "cell_type", std::string("uint8"));
      std::vector<std::uint8_t> bytes(cells_.size());
      for (int iy = 0; iy < geometry_.ny; ++iy)
        for (int ix = 0; ix < geometry_.nx; ++ix)
          bytes[iy * geometry_.nx + ix] = EncodeCell(cells_(iy, ix));
      f->Write("/cells", bytes.data(), shape);
    } else {
      f->SetAttr("/model", "cell_type", std::string("float32"));
      f->WriteMatrix("/cells", cells_);
    }
  });
}

GridMap GridMap::Load(const std::string& path) {
  Artifact a = Artifact::Open(path, kGridMapType);
  const h5::File& f = a.file();
  GridGeometry g;
  g.x_min = a.DoubleAttr("/model", "x_min", -1e9, 1e9);
  g.y_min = a.DoubleAttr("/model", "y_min", -1e9, 1e9);
  g.resolution = a.DoubleAttr("/model", "resolution", 1e-9, 1e9);
  const std::int64_t nx = a.IntAttr("/model", "nx", 1, 1 << 20),
                     ny = a.IntAttr("/model", "ny", 1, 1 << 20);
  FS_THROW_UNLESS(nx * ny <= (std::int64_t{1} << 30), path, ": grid of ", nx, " x ", ny,
                  " cells is too large");
  g.nx = static_cast<int>(nx);
  g.ny = static_cast<int>(ny);
  const std::string type = f.GetStringAttr("/model", "cell_type");
  try {
    if (type == "uint8") {
      const h5::Array<std::uint8_t> bytes = f.ReadUint8("/cells");
      const std::vector<std::size_t> expected{std::size_t(ny), std::size_t(nx)};
      FS_THROW_UNLESS(bytes.shape == expected, "/cells has the wrong shape");
      Eigen::MatrixXf p(ny, nx);
      for (int iy = 0; iy < g.ny; ++iy)
        for (int ix = 0; ix < g.nx; ++ix) {
          const std::uint8_t q = bytes.data[iy * g.nx + ix];
          p(iy, ix) = q == 255 ? std::numeric_limits<float>::quiet_NaN() : DecodeCell(q);
        }
      return GridMap(g, std::move(p), CellType::kUint8);
    }
    FS_THROW_UNLESS(type == "float32", "cell_type '", type, "' is not float32 or uint8");
    return GridMap(g, f.ReadMatrixF("/cells", ny, nx), CellType::kFloat32);
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind(path, 0) == 0) throw;
    Fail(path, ": ", what);
  }
}

}  // namespace foresight::occupancy
