// Directional-map queries allocate nothing once the workspace and the output batch are sized (own
// binary: it replaces the global operator new to count allocations).

#include <gtest/gtest.h>

#include <cmath>

#include "inference/directional/directional_map.h"
#include "tests/alloc_counter.h"  // replaces operator new: one per binary
#include "tests/inference/directional_test_util.h"

namespace foresight::directional {
namespace {

TEST(DirectionalMapQueries, AllocateNothingWhenSized) {
  for (const Variant v : {Variant::kSpatiotemporal, Variant::kSpatial}) {
    const Map m = testing::RandomDirectionalMap(v, testing::SmallFeatureConfig(), 16, 5, 1);
    auto ws = m.MakeWorkspace();
    const int n = 300;
    // Inside, outside the extent, outside the time range.
    const Eigen::VectorXd x = Eigen::VectorXd::Random(n) * 12.0 + Eigen::VectorXd::Constant(n, 5.0);
    const Eigen::VectorXd y = Eigen::VectorXd::Random(n) * 8.0 + Eigen::VectorXd::Constant(n, 2.0);
    const Eigen::VectorXd t =
        Eigen::VectorXd::Random(n) * 80.0 + Eigen::VectorXd::Constant(n, 30.0);
    const Eigen::VectorXd theta = Eigen::VectorXd::Random(n) * 3.0;
    VonMisesMixtureBatch batch;
    Eigen::VectorXd density(n);
    m.Query(x, y, t, &ws, &batch);  // sizes the batch
    g_allocations = 0;
    g_counting = true;
    m.Query(x, y, t, &ws, &batch);
    m.Density(x, y, t, theta, &ws, density);
    for (int i = 0; i < 20; ++i) m.QueryOne(x[i], y[i], t[i], &ws);
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << VariantName(v) << ": heap allocations on the query path";
    EXPECT_TRUE(density.allFinite());
    EXPECT_TRUE(batch.alpha.allFinite());
  }
}

}  // namespace
}  // namespace foresight::directional
