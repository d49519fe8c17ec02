// Fuzz target: LoadOccupancyMap on edited valid hinge-map (Hilbert, Fast-BHM, BHM; float32 and
// float64 weights) and grid-map (float32 and uint8 cells) artifacts written by the maps' own Save
// (tests/fuzz/h5_mutator.h); the first input byte picks the artifact. A map that loads must answer
// finite queries with finite probabilities, gradients and variances.
#include <cmath>

#include "core/hinge_grid.h"
#include "inference/mapping/grid_map.h"
#include "inference/mapping/hinge_map.h"
#include "inference/mapping/occupancy_map.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/h5_mutator.h"
#include "tests/occupancy_test_util.h"

namespace {

std::vector<std::uint8_t> HingeBase(foresight::occupancy::HingeMapKind kind,
                                    foresight::occupancy::StoredPrecision p,
                                    const std::string& name) {
  using namespace foresight;
  const occupancy::HingeMap map =
      testing::RandomHingeMap(kind, HingeGrid(testing::SmallGrid(2.0, 1.5, 4.0, 1.0)), 1, 0.3, 5.0);
  const std::string path = fuzz::ScratchPath(name);
  map.Save(path, "model: occupancy\n", 0, p);
  return fuzz::ReadFileBytes(path);
}

std::vector<std::uint8_t> GridBase(foresight::occupancy::CellType type, const std::string& name) {
  using namespace foresight;
  occupancy::GridGeometry g;
  g.x_min = -1;
  g.y_min = -2;
  g.resolution = 0.5;
  g.nx = 5;
  g.ny = 4;
  Eigen::MatrixXf p(g.ny, g.nx);
  for (int i = 0; i < p.size(); ++i) p.data()[i] = static_cast<float>(i % 7) / 6.0f;
  p(1, 1) = std::nanf("");  // unknown
  const occupancy::GridMap map(g, p, type);
  const std::string path = fuzz::ScratchPath(name);
  map.Save(path, "model: grid\n", 0);
  return fuzz::ReadFileBytes(path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace foresight;
  static const std::vector<std::uint8_t> bases[] = {
      HingeBase(occupancy::HingeMapKind::kHilbert, occupancy::StoredPrecision::kFloat32,
                "base_hilbert.h5"),
      HingeBase(occupancy::HingeMapKind::kFastBhm, occupancy::StoredPrecision::kFloat64,
                "base_fastbhm.h5"),
      HingeBase(occupancy::HingeMapKind::kBhm, occupancy::StoredPrecision::kFloat32, "base_bhm.h5"),
      GridBase(occupancy::CellType::kFloat32, "base_grid_f32.h5"),
      GridBase(occupancy::CellType::kUint8, "base_grid_u8.h5")};
  constexpr int kBases = sizeof(bases) / sizeof(bases[0]);
  fuzz::ByteReader in(data, size);
  const int kind = in.Byte() % kBases;
  const std::string path = fuzz::WriteScratch("occ.h5", bases[kind].data(), bases[kind].size());
  fuzz::MutateH5(path, &in);
  fuzz::ExpectCleanError(path, [&] {
    const auto map = occupancy::LoadMap(path);
    auto ws = map->MakeWorkspace();
    bool finite = map->Extent().allFinite();
    for (const auto& xy : {Eigen::Vector2d(0.7, 0.4), Eigen::Vector2d(-0.2, -1.1),
                           Eigen::Vector2d(1.3, 0.9), Eigen::Vector2d(30.0, -30.0)}) {
      const occupancy::QueryResult q = map->Query(xy.x(), xy.y(), &ws);
      finite = finite && std::isfinite(q.probability) && std::isfinite(q.dp_dx) &&
               std::isfinite(q.dp_dy) && std::isfinite(q.variance) && q.probability >= 0 &&
               q.probability <= 1 && std::isfinite(map->Probability(xy.x(), xy.y(), &ws));
    }
    fuzz::ExpectFiniteAnswer(finite, path, "an occupancy query");
  });
  return 0;
}
