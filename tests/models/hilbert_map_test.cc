// Hilbert map SGD on a simple synthetic room: walls occupied, the inside free.

#include "models/occupancy/hilbert_map.h"

#include <gtest/gtest.h>

#include <random>

#include "core/binary_metrics.h"
#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::occupancy {
namespace {

/// Hits on the walls of the room [0, 8] x [0, 6] (with 2 cm noise), free points inside, 0.5 m
/// away from the walls.
testing::PointSet Room(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.02);
  testing::PointSet p;
  p.xy.resize(2, n);
  p.occupied.resize(n);
  for (int i = 0; i < n; ++i) {
    if (u(rng) < 0.4) {
      const double s = u(rng) * 28.0;  // perimeter
      Eigen::Vector2d q = s < 8    ? Eigen::Vector2d(s, 0)
                          : s < 14 ? Eigen::Vector2d(8, s - 8)
                          : s < 22 ? Eigen::Vector2d(22 - s, 6)
                                   : Eigen::Vector2d(0, 28 - s);
      p.xy.col(i) = q + Eigen::Vector2d(noise(rng), noise(rng));
      p.occupied[i] = 1;
    } else {
      p.xy.col(i) << 0.5 + 7 * u(rng), 0.5 + 5 * u(rng);
      p.occupied[i] = 0;
    }
  }
  return p;
}

HingeGrid RoomGrid() {
  HingeGridConfig c;
  c.x_min = -1;
  c.x_max = 9;
  c.y_min = -1;
  c.y_max = 7;
  return HingeGrid(c);  // 20 x 16, spacing 0.5, gamma 6.71, cut-off 1 m
}

double Auc(const HingeMap& map, const testing::PointSet& p) {
  MapWorkspace ws = map.MakeWorkspace();
  std::vector<double> scores;
  for (Eigen::Index i = 0; i < p.xy.cols(); ++i)
    scores.push_back(map.Probability(p.xy(0, i), p.xy(1, i), &ws));
  return EvaluateBinary(scores, p.occupied).auc;
}

TEST(HilbertMap, SeparatesWallsFromFreeSpace) {
  const testing::PointSet train = Room(3000, 1), test = Room(2000, 2);
  HilbertMapConfig cfg;
  cfg.epochs = 2;
  const HingeMap map = TrainHilbertMap(RoomGrid(), cfg, train.xy, train.occupied.data(), 7);
  EXPECT_EQ(map.kind(), HingeMapKind::kHilbert);
  EXPECT_EQ(map.weights().variance.size(), 0);
  const double auc = Auc(map, test);
  EXPECT_GT(auc, 0.95);
  // Probabilities point the right way: a wall is likely occupied, the room centre free.
  MapWorkspace ws = map.MakeWorkspace();
  EXPECT_GT(map.Probability(4.0, 0.0, &ws), 0.5);
  EXPECT_LT(map.Probability(4.0, 3.0, &ws), 0.5);
}

TEST(HilbertMap, IsDeterministicInTheSeed) {
  const testing::PointSet train = Room(800, 3);
  const HilbertMapConfig cfg;
  const HingeMap a = TrainHilbertMap(RoomGrid(), cfg, train.xy, train.occupied.data(), 5);
  const HingeMap b = TrainHilbertMap(RoomGrid(), cfg, train.xy, train.occupied.data(), 5);
  const HingeMap c = TrainHilbertMap(RoomGrid(), cfg, train.xy, train.occupied.data(), 6);
  EXPECT_EQ(a.weights().mean, b.weights().mean);
  EXPECT_GT((a.weights().mean - c.weights().mean).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(HilbertMap, PureL1PenaltyZeroesWeightsAndNoPointsIsAnError) {
  const testing::PointSet train = Room(800, 4);
  HilbertMapConfig cfg;
  cfg.alpha = 0.05;
  cfg.l1_ratio = 1.0;
  const HingeMap sparse = TrainHilbertMap(RoomGrid(), cfg, train.xy, train.occupied.data(), 1);
  cfg.alpha = 0;
  const HingeMap dense = TrainHilbertMap(RoomGrid(), cfg, train.xy, train.occupied.data(), 1);
  const auto zeros = [](const HingeMap& m) { return (m.weights().mean.array() == 0).count(); };
  EXPECT_GT(zeros(sparse), zeros(dense) + 20);
  testing::ExpectErrorContains(
      [&] { TrainHilbertMap(RoomGrid(), HilbertMapConfig{}, Eigen::Matrix2Xd(2, 0), nullptr, 1); },
      {"no training points"});
}

}  // namespace
}  // namespace foresight::occupancy
