// The engine's hot paths allocate nothing once the workspaces exist (own binary: it replaces the
// global operator new, and malloc, to count allocations). Speed: `foresight bench ARTIFACT`.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "inference/imitation/transforms.h"
#define FORESIGHT_ALLOC_COUNTER_MALLOC  // count Eigen's malloc too
#include "tests/alloc_counter.h"        // replaces operator new: one per binary

namespace foresight::imitation {
namespace {

// The thesis's LASA setting: 720 inducing states (30 x 24), ~49 inside the cut-off, K = 10.
RbfGrid<2> LasaGrid() {
  RbfGridSpec<2> s;
  s.lower = Vec<2>(-1.5, -1.2);
  s.counts = {30, 24};
  s.spacing = 0.1;
  s.gamma = 120;
  s.cutoff_radius = 0.4;
  return RbfGrid<2>(s);
}

Eigen::VectorXd RandomVector(int n, double scale, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::VectorXd v(n);
  for (auto& x : v) x = scale * n01(rng);
  return v;
}

struct Fixture {
  Fixture()
      : grid(LasaGrid()),
        system(RbfFlow<2>(grid,
                          Eigen::Map<const Eigen::MatrixXd>(
                              RandomVector(grid.size() * 2, 0.05, 1).data(), grid.size(), 2),
                          {1.0, 10}),
               Vec<2>(0.2, -0.1), 1.0),
        field(grid, RandomVector(grid.size(), 1.0, 2), -1.0) {
    OuterTransform<2> obstacle;
    obstacle.obstacle = ObstacleTransform<2>(field, {0.05, 10});
    OuterTransform<2> bias;
    bias.type = OuterTransform<2>::Type::kBias;
    bias.bias = RbfFlow<2>(grid,
                           Eigen::Map<const Eigen::MatrixXd>(
                               RandomVector(grid.size() * 2, 0.03, 3).data(), grid.size(), 2),
                           {0.5, 10});
    composed_one.emplace_back(system, std::vector<OuterTransform<2>>{obstacle});
    composed_two.emplace_back(system, std::vector<OuterTransform<2>>{obstacle, bias});
  }
  RbfGrid<2> grid;
  ImitationSystem<2> system;
  OccupancyField<2> field;
  std::vector<ComposedSystem<2>> composed_one, composed_two;
};

TEST(ImitationHotPaths, AllocateNothingAfterSetUp) {
  const Fixture fx;
  FlowWorkspace<2> fws = fx.system.flow().MakeWorkspace();
  auto ows = fx.field.MakeWorkspace();
  ComposedWorkspace<2> c1 = fx.composed_one[0].MakeWorkspace();
  ComposedWorkspace<2> c2 = fx.composed_two[0].MakeWorkspace();
  const ObstacleTransform<2> obstacle(fx.field, {0.05, 10});
  OccupancyField<2> table = fx.field;  // the bicubic table's path (obstacle.map_table_spacing)
  table.Tabulate(0.01);
  const ObstacleTransform<2> tabulated(table, {0.05, 10});
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix2Xd points(2, 100);
  for (Eigen::Index i = 0; i < points.size(); ++i) points.data()[i] = u(rng);
  points.col(0) << std::nan(""), 0.0;  // non-finite input must not allocate either
  auto exercise = [&]() {
    double sink = 0;
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const Vec<2> y = points.col(i);
      Mat<2> j;
      Vec<2> x, z;
      sink += fx.system.flow().Forward(y, &fws, &j).sum() + j.sum();
      if (fx.system.flow().Inverse(y, &fws, &x)) sink += x.sum();
      sink += fx.system.Velocity(y, &fws, &z).sum();
      OccupancyValue<2> v;
      fx.field.Evaluate(y, ows.get(), true, &v);
      sink += v.p + v.gradient.sum() + v.hessian.sum() + fx.field.Probability(y, ows.get());
      sink += obstacle.Forward(y, ows.get(), &j).sum();
      if (obstacle.Inverse(y, ows.get(), &x)) sink += x.sum();
      table.Evaluate(y, ows.get(), true, &v);
      sink += v.p + v.hessian.sum() + table.Probability(y, ows.get());
      sink += tabulated.Forward(y, ows.get(), &j).sum();
      if (tabulated.Inverse(y, ows.get(), &x)) sink += x.sum();
      sink += fx.composed_one[0].Velocity(y, &c1).sum() + fx.composed_two[0].Velocity(y, &c2).sum();
      sink += fx.composed_two[0].Inner(y, &c2).sum();
    }
    return sink;
  };
  exercise();  // warm-up
  g_allocations = 0;
  g_counting = true;
  const double sink = exercise();
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0) << "heap allocations on the hot paths";
  EXPECT_FALSE(std::isinf(sink));
}

}  // namespace
}  // namespace foresight::imitation
