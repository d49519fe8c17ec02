// OTNet's pipeline pieces against independent computations: the pruned MTD equals the brute-force
// mean minimum distance; the greedy farthest-point database; and the pipeline on synthetic data.

#include <gtest/gtest.h>

#include <random>

#include "datasets/synthetic_rooms.h"
#include "tests/test_util.h"
#include "training/otnet/data.h"
#include "training/otnet/eval.h"
#include "training/otnet/transfer.h"

namespace foresight::otnet {
namespace {

Eigen::MatrixX2d RandomWalk(std::mt19937_64* rng, int n, Eigen::Vector2d start) {
  std::normal_distribution<double> step(0.0, 1.0);
  Eigen::MatrixX2d t(n, 2);
  t.row(0) = start.transpose();
  for (int i = 1; i < n; ++i) t.row(i) = t.row(i - 1) + Eigen::RowVector2d(step(*rng), step(*rng));
  return t;
}

TEST(OtnetPipeline, PrunedMinimumDistanceEqualsBruteForce) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 30);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::MatrixX2d> truth, generated;
    for (int i = 0; i < 25; ++i) truth.push_back(RandomWalk(&rng, 30, {u(rng), u(rng)}));
    for (int i = 0; i < 5; ++i) generated.push_back(RandomWalk(&rng, 30, {u(rng), u(rng)}));
    for (TrajectoryDistance d : {TrajectoryDistance::kHausdorff, TrajectoryDistance::kFrechet}) {
      double mean = 0;
      for (const auto& g : generated) mean += MinimumDistance(g, truth, d);
      mean /= generated.size();
      EXPECT_NEAR(mean, MeanMinimumDistance(generated, truth, d), 1e-12);
    }
  }
}

TEST(OtnetPipeline, MinimumDistanceOfAMemberIsZero) {
  std::mt19937_64 rng(4);
  std::vector<Eigen::MatrixX2d> truth;
  for (int i = 0; i < 10; ++i) truth.push_back(RandomWalk(&rng, 20, {5.0 * i, 0}));
  EXPECT_EQ(MinimumDistance(truth[7], truth, TrajectoryDistance::kFrechet), 0.0);
  EXPECT_EQ(MinimumDistance(truth[3], truth, TrajectoryDistance::kHausdorff), 0.0);
}

TEST(OtnetPipeline, FarthestPointDatabaseSpreadsOverTheMaps) {
  SyntheticRoomsOptions o;
  o.maps = 12;
  o.trajectories_per_map = 2;
  const std::vector<MapTrajectories> maps = GenerateRoomsAndCorridors(o);
  EXPECT_EQ(ChooseDatabase(maps, 0).size(), 12u);
  EXPECT_EQ(ChooseDatabase(maps, 50).size(), 12u);
  const std::vector<int> chosen = ChooseDatabase(maps, 4);
  ASSERT_EQ(chosen.size(), 4u);
  // Brute force: the greedy k-centre objective (largest distance of any map to its nearest chosen
  // one) is no worse than that of the first four maps, and the choice has no duplicates.
  std::vector<std::vector<Eigen::Vector2i>> edges;
  for (const auto& m : maps) edges.push_back(EdgeCells(m.map));
  const auto radius = [&](const std::vector<int>& set) {
    double worst = 0;
    for (std::size_t i = 0; i < maps.size(); ++i) {
      double best = 1e300;
      for (int j : set) best = std::min(best, AveragedHausdorffBruteForce(edges[i], edges[j]));
      worst = std::max(worst, best);
    }
    return worst;
  };
  EXPECT_LE(radius(chosen), radius({0, 1, 2, 3}) + 1e-9);
  for (std::size_t i = 1; i < chosen.size(); ++i) EXPECT_LT(chosen[i - 1], chosen[i]);
}

TEST(OtnetPipeline, BorderOpeningsAreTheLongestFreeRunsOfTheBorder) {
  BinaryGrid g(10, 8);
  for (int r = 0; r < 8; ++r)
    for (int c = 0; c < 10; ++c) g.at(r, c) = (r == 0 || r == 7 || c == 0 || c == 9);
  // A 3-cell gap in the top wall (columns 4..6) and a 1-cell gap in the left wall (row 5).
  for (int c = 4; c <= 6; ++c) g.at(0, c) = 0;
  g.at(5, 0) = 0;
  const std::vector<Eigen::Vector2d> o = BorderOpenings(g, 5);
  ASSERT_EQ(o.size(), 2u);
  EXPECT_TRUE(o[0].isApprox(Eigen::Vector2d(5.5, 1.5))) << o[0].transpose();
  EXPECT_TRUE(o[1].isApprox(Eigen::Vector2d(1.5, 5.5))) << o[1].transpose();
  EXPECT_EQ(BorderOpenings(g, 1).size(), 1u);
  // A gap through the corner where the walk starts is one run, not two.
  g.at(0, 0) = 0;
  g.at(1, 0) = 0;
  g.at(0, 1) = 0;
  EXPECT_EQ(BorderOpenings(g, 5).size(), 3u);
  // No opening: nothing to start from.
  BinaryGrid closed(6, 6);
  for (auto& v : closed.cells) v = 1;
  EXPECT_TRUE(BorderOpenings(closed, 2).empty());
}

}  // namespace
}  // namespace foresight::otnet
