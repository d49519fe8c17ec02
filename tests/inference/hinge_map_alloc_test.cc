// Occupancy-map queries allocate nothing once the workspace exists (own binary: it replaces the
// global operator new to count allocations).

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "inference/mapping/grid_map.h"
#include "inference/mapping/hinge_map.h"
#include "tests/alloc_counter.h"  // replaces operator new: one per binary
#include "tests/occupancy_test_util.h"

namespace foresight::occupancy {
namespace {

double Exercise(const Map& map, MapWorkspace* ws, const Eigen::Matrix2Xd& pts, MapQueryBatch* batch,
                Eigen::VectorXd* probabilities) {
  double sink = 0;
  for (Eigen::Index i = 0; i < pts.cols(); ++i) {
    const QueryResult q = map.Query(pts(0, i), pts(1, i), ws);
    sink +=
        q.probability + q.dp_dx + q.dp_dy + q.variance + map.Probability(pts(0, i), pts(1, i), ws);
  }
  map.QueryBatch(pts, ws, batch);
  map.ProbabilityBatch(pts, ws, *probabilities);
  return sink + batch->probability.sum() + probabilities->sum();
}

TEST(OccupancyMapQueries, AllocateNothingAfterSetUp) {
  HingeGridConfig c;
  c.x_min = 0;
  c.x_max = 5;
  c.y_min = 0;
  c.y_max = 4;
  const HingeGrid grid(c);
  std::vector<std::unique_ptr<Map>> maps;
  for (const HingeMapKind kind :
       {HingeMapKind::kHilbert, HingeMapKind::kFastBhm, HingeMapKind::kBhm})
    maps.push_back(std::make_unique<HingeMap>(testing::RandomHingeMap(kind, grid, 1)));
  maps.push_back(std::make_unique<GridMap>(
      GridGeometry{0, 0, 0.1, 50, 40}, Eigen::MatrixXf::Constant(40, 50, 0.3f), CellType::kUint8));
  // Inside, at the edges, outside and NaN.
  Eigen::Matrix2Xd pts =
      Eigen::Matrix2Xd::Random(2, 200) * 4.0 + Eigen::Vector2d(2.5, 2.0).replicate(1, 200);
  pts.col(0) << std::nan(""), 1.0;
  pts.col(1) << 1e300, -1e300;
  for (const auto& map : maps) {
    MapWorkspace ws = map->MakeWorkspace();
    MapQueryBatch batch;
    batch.Resize(pts.cols());
    Eigen::VectorXd probabilities(pts.cols());
    Exercise(*map, &ws, pts, &batch, &probabilities);  // warm-up
    g_allocations = 0;
    g_counting = true;
    const double sink = Exercise(*map, &ws, pts, &batch, &probabilities);
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0)
        << map->model_type() << ": heap allocations on the query path";
    EXPECT_TRUE(std::isfinite(sink));
  }
}

}  // namespace
}  // namespace foresight::occupancy
