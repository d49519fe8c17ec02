// OTNet's pipeline pieces against independent computations: the pruned MTD equals the brute-force
// mean minimum distance; the greedy farthest-point database; the symmetric copies of the training
// maps; and the pipeline on synthetic data.

#include <gtest/gtest.h>

#include <algorithm>
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

// A 6 x 6 map with no symmetry of its own (an L of walls and one pillar off the diagonals) and a
// trajectory through free cells at cell centres and off-centre points.
MapTrajectories AsymmetricMap() {
  MapTrajectories m;
  m.id = "asym";
  m.map = BinaryGrid(6, 6);
  for (int c = 0; c < 6; ++c) m.map.at(0, c) = 1;
  for (int r = 0; r < 6; ++r) m.map.at(r, 0) = 1;
  m.map.at(3, 4) = 1;
  Eigen::MatrixX2d t(4, 2);
  t << 1.5, 1.5, 2.25, 3.75, 3.1, 4.9, 5.6, 2.2;
  m.trajectories = {t};
  return m;
}

TEST(OtnetAugment, EverySymmetryKeepsEachWaypointInTheImageOfItsCell) {
  const MapTrajectories m = AsymmetricMap();
  std::vector<std::vector<std::uint8_t>> seen;
  for (int s = 0; s < 8; ++s) {
    int dropped = 0;
    const MapTrajectories t = TransformMap(m, s, &dropped);
    EXPECT_EQ(dropped, 0);
    EXPECT_EQ(t.map.CountOccupied(), m.map.CountOccupied());
    ASSERT_EQ(t.trajectories.size(), 1u);
    // By hand: the cell of (x, y) after the swap (y, x) and the reflections n - x, n - y.
    const Eigen::MatrixX2d& a = m.trajectories[0];
    const Eigen::MatrixX2d& b = t.trajectories[0];
    for (Eigen::Index k = 0; k < a.rows(); ++k) {
      double x = a(k, 0), y = a(k, 1);
      if (s & 4) std::swap(x, y);
      if (s & 1) x = 6 - x;
      if (s & 2) y = 6 - y;
      EXPECT_DOUBLE_EQ(b(k, 0), x);
      EXPECT_DOUBLE_EQ(b(k, 1), y);
      EXPECT_FALSE(t.map.OccupiedAt(x, y));
    }
    // Every cell of the copy holds the value of its preimage.
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) {
        int x = s & 4 ? r : c, y = s & 4 ? c : r;
        if (s & 1) x = 5 - x;
        if (s & 2) y = 5 - y;
        EXPECT_EQ(t.map.at(y, x), m.map.at(r, c)) << "s " << s << " cell " << r << ", " << c;
      }
    seen.push_back(t.map.cells);
  }
  // The 8 copies of a map without symmetry are distinct, and a reflection twice is the identity.
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::unique(seen.begin(), seen.end()), seen.end());
  int dropped = 0;
  const MapTrajectories twice = TransformMap(TransformMap(m, 1, &dropped), 1, &dropped);
  EXPECT_EQ(twice.map.cells, m.map.cells);
  EXPECT_TRUE(twice.trajectories[0].isApprox(m.trajectories[0], 1e-15));
}

TEST(OtnetAugment, AveragedHausdorffIsInvariantUnderTheSameSymmetry) {
  // The encoder's similarity is a distance between edge sets: moving both maps by one symmetry
  // keeps it (an independent check that maps are transformed as rigid motions of the grid).
  SyntheticRoomsOptions o;
  o.maps = 2;
  o.trajectories_per_map = 1;
  const std::vector<MapTrajectories> maps = GenerateRoomsAndCorridors(o);
  const double d0 = AveragedHausdorffBruteForce(EdgeCells(maps[0].map), EdgeCells(maps[1].map));
  ASSERT_GT(d0, 0);
  for (int s = 1; s < 8; ++s) {
    int dropped = 0;
    const BinaryGrid a = TransformMap(maps[0], s, &dropped).map;
    const BinaryGrid b = TransformMap(maps[1], s, &dropped).map;
    EXPECT_NEAR(AveragedHausdorffBruteForce(EdgeCells(a), EdgeCells(b)), d0, 1e-12) << s;
  }
}

TEST(OtnetAugment, BoundaryWaypointsNextToAWallAreDroppedAndCounted) {
  MapTrajectories m = AsymmetricMap();
  // x = 1.0 lies on the boundary between the wall column 0 and the free column 1: free as read,
  // inside the reflected wall after x -> 6 - x (5.0 is column 5, the image of column 0).
  Eigen::MatrixX2d on_edge(2, 2);
  on_edge << 1.0, 2.5, 2.5, 2.5;
  m.trajectories.push_back(on_edge);
  int dropped = 0;
  EXPECT_EQ(TransformMap(m, 1, &dropped).trajectories.size(), 1u);
  EXPECT_EQ(dropped, 1);
  MapTrajectories wide = m;
  wide.map = BinaryGrid(6, 5);
  testing::ExpectErrorContains([&] { TransformMap(wide, 1, &dropped); },
                               {"asym", "6 x 5", "square"});
}

TEST(OtnetAugment, OnlyTheTrainingMapsAreCopiedAndTheDatabaseKeepsTheMapsAsRead) {
  ExperimentConfig c;
  c.data.source = Source::kSynthetic;
  c.data.synthetic_maps = 24;
  c.data.synthetic_trajectories = 3;
  c.data.synthetic_layouts = 12;
  const OtnetData plain = LoadOtnetData(c);
  c.data.augment = Augment::kDihedral;
  const OtnetData aug = LoadOtnetData(c);
  const std::size_t n = plain.train.maps.size();
  ASSERT_EQ(aug.train.maps.size(), 8 * n);
  EXPECT_EQ(aug.train.copies, static_cast<int>(7 * n));
  EXPECT_EQ(aug.val.maps.size(), plain.val.maps.size());
  EXPECT_EQ(aug.test.maps.size(), plain.test.maps.size());
  EXPECT_EQ(aug.val.copies + aug.test.copies, 0);
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(aug.train.maps[i].id, plain.train.maps[i].id);
  EXPECT_EQ(aug.train.maps[n].id, plain.train.maps[0].id + "@s1");
  EXPECT_EQ(MakeEncoder(c, aug.train).size(), static_cast<int>(n));
}

}  // namespace
}  // namespace foresight::otnet
