// CollisionCost::Component (with and without gradient) and Mixture allocate nothing once the
// workspace and the gradient are sized (own binary: it replaces the global allocators).

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/hinge_grid.h"
#include "inference/constrained/collision_cost.h"
#include "inference/mapping/hinge_map.h"
#include "tests/occupancy_test_util.h"
#define FORESIGHT_ALLOC_COUNTER_MALLOC  // count Eigen's malloc too
#include "tests/alloc_counter.h"        // replaces operator new: one per binary

namespace foresight::constrained {
namespace {

class SmoothHalfPlane final : public occupancy::Map {
 public:
  std::string model_type() const override { return "test.smooth_half_plane"; }
  occupancy::MapWorkspace MakeWorkspace() const override { return {}; }
  occupancy::QueryResult Query(double x, double y, occupancy::MapWorkspace*) const override {
    occupancy::QueryResult q;
    q.probability = 1 / (1 + std::exp(-3 * (0.6 * x + 0.8 * y - 0.2)));
    q.dp_dx = 3 * q.probability * (1 - q.probability) * 0.6;
    q.dp_dy = 3 * q.probability * (1 - q.probability) * 0.8;
    return q;
  }
  Eigen::Vector4d Extent() const override { return {-1e3, 1e3, -1e3, 1e3}; }
};

ComponentParams Component(const TimeBasis& basis, double x0, double y0) {
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(20, 0.0, 4.8);
  Eigen::MatrixXd points(20, 2);
  for (int i = 0; i < 20; ++i) points.row(i) << x0 + 0.6 * t[i], y0 + 0.4 * t[i];
  ComponentParams c;
  c.mean = basis.FitRidge(t, points, 1e-3);
  c.log_u = Eigen::VectorXd::LinSpaced(basis.size(), -3.0, -2.0);
  c.chol_v << 1.1, 0, 0.2, 0.8;
  return c;
}

void ExpectNoAllocation(const occupancy::Map& map, const ComponentParams& c0,
                        const ComponentParams& c1, const TimeBasis& basis) {
  const CollisionCost cost(&map, basis, Eigen::VectorXd::LinSpaced(12, 0.2, 4.6), 8);
  CollisionCost::Workspace ws = cost.MakeWorkspace();
  ComponentGradient g;
  const std::vector<ComponentParams> comps = {c0, c1};
  const std::vector<double> alpha = {0.7, 0.3};
  double sink = cost.Component(c0, &ws, &g);  // warm-up: sizes the gradient
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < 3; ++i) {
    sink += cost.Component(c0, &ws, &g);
    sink += cost.Component(c1, &ws, &g);
    sink += cost.Component(c1, &ws, nullptr);
    sink += cost.Mixture(alpha, comps, &ws);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0) << map.model_type();
  EXPECT_TRUE(std::isfinite(sink));
  EXPECT_GT(g.mean.cwiseAbs().maxCoeff(), 0.0);
}

TEST(CollisionCostHotPath, ComponentAllocatesNothingAfterWarmUp) {
#ifndef FORESIGHT_COUNTS_MALLOC
  GTEST_SKIP() << "malloc is not counted in this build (neither glibc nor AddressSanitizer); "
                  "operator new only";
#endif
  const TimeBasis basis(8, 0.0, 4.8, 1.0);
  const SmoothHalfPlane plane;
  ExpectNoAllocation(plane, Component(basis, -1.5, -1.0), Component(basis, 0.0, -2.0), basis);
  const HingeGrid grid(testing::SmallGrid(8, 8, 1.0, 3.5));
  const occupancy::HingeMap hilbert =
      testing::RandomHingeMap(occupancy::HingeMapKind::kHilbert, grid, 7);
  ExpectNoAllocation(hilbert, Component(basis, 2.5, 3.0), Component(basis, 3.0, 2.0), basis);
}

}  // namespace
}  // namespace foresight::constrained
