#include "models/span/span_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"

namespace foresight::span {
namespace {

WindowSet StraightWalk(double vx, double vy) {
  TrackSet set;
  Track t;
  t.positions.resize(20, 2);
  for (int i = 0; i < 20; ++i) {
    t.time.push_back(0.4 * i);
    t.positions.row(i) << 3.0 + vx * 0.4 * i, -1.0 + vy * 0.4 * i;
  }
  set.tracks.push_back(t);
  return MakeWindows(set, WindowConfig{8, 12, 1});
}

TEST(SpanSamples, EgoFrameInputsAndTargetsOfAStraightWalk) {
  const WindowSet w = StraightWalk(0.6, 0.8);  // 1 m/s at 53 degrees
  TrajectoryBasisConfig c;
  const TimeBasis basis = MakeFutureBasis(c, 12, 0.4);
  const Samples s = MakeSamples(w, basis, c, true);
  ASSERT_EQ(s.inputs.rows(), 1);
  // Ego frame: the last point is the origin, the walk lies on the -x axis.
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(s.inputs(0, 2 * i), -0.4 * (7 - i), 1e-12);
    EXPECT_NEAR(s.inputs(0, 2 * i + 1), 0.0, 1e-12);
  }
  // The fitted future follows +x at 1 m/s.
  Eigen::MatrixXd wm(basis.size(), 2);
  for (int j = 0; j < basis.size(); ++j) wm.row(j) << s.targets(0, 2 * j), s.targets(0, 2 * j + 1);
  for (double t : {0.4, 2.0, 4.8}) {
    const Eigen::Vector2d o = wm.transpose() * basis.Evaluate(t);
    EXPECT_NEAR(o.x(), t, 0.01);
    EXPECT_NEAR(o.y(), 0.0, 1e-9);
  }
  // Relative to constant velocity the residual of a straight walk is zero.
  const Samples r = MakeSamples(w, basis, c, true, /*residual_to_constant_velocity=*/true);
  EXPECT_LT(r.targets.cwiseAbs().maxCoeff(), 1e-9);
}

// A walk that turns and speeds up, transformed in world coordinates by (x, y) -> (sx x, sy y).
WindowSet CurvedWalk(double sx, double sy) {
  TrackSet set;
  Track t;
  t.positions.resize(25, 2);
  for (int i = 0; i < 25; ++i) {
    const double a = 0.08 * i, r = 4.0 + 0.1 * i;
    t.time.push_back(0.4 * i);
    t.positions.row(i) << sx * (1.0 + r * std::cos(a)), sy * (2.0 + r * std::sin(a));
  }
  set.tracks.push_back(t);
  return MakeWindows(set, WindowConfig{8, 12, 1});
}

// The augmented samples are the samples of the scaled and mirrored walks, computed from scratch.
TEST(SpanSamples, AugmentIsExactlyTheSamplesOfScaledAndMirroredWalks) {
  TrajectoryBasisConfig c;
  const TimeBasis basis = MakeFutureBasis(c, 12, 0.4);
  for (const bool residual : {false, true}) {
    const auto samples = [&](double sx, double sy) {
      return MakeSamples(CurvedWalk(sx, sy), basis, c, true, residual);
    };
    AugmentConfig a;
    a.speed_scales = {0.5, 2.0};
    a.mirror = true;
    const Samples base = samples(1, 1);
    ASSERT_EQ(base.inputs.rows(), 6);
    const Samples aug = Augment(base, a);
    ASSERT_EQ(aug.inputs.rows(), 6 * a.Copies());
    ASSERT_EQ(a.Copies(), 6);
    const std::vector<Samples> expected = {samples(1, 1),  samples(0.5, 0.5),  samples(2, 2),
                                           samples(1, -1), samples(0.5, -0.5), samples(2, -2)};
    for (std::size_t k = 0; k < expected.size(); ++k) {
      EXPECT_LT((aug.inputs.middleRows(6 * static_cast<Eigen::Index>(k), 6) - expected[k].inputs)
                    .cwiseAbs()
                    .maxCoeff(),
                1e-9)
          << "copy " << k << " residual " << residual;
      EXPECT_LT((aug.targets.middleRows(6 * static_cast<Eigen::Index>(k), 6) - expected[k].targets)
                    .cwiseAbs()
                    .maxCoeff(),
                1e-9)
          << "copy " << k << " residual " << residual;
    }
  }
  // No augmentation returns the samples unchanged.
  const Samples base = MakeSamples(CurvedWalk(1, 1), basis, c, true);
  const Samples same = Augment(base, AugmentConfig{});
  EXPECT_EQ(same.inputs, base.inputs);
  EXPECT_EQ(same.targets, base.targets);
}

TEST(SpanSamples, AugmentRefusesAScaleOfOneOrBelowZero) {
  TrajectoryBasisConfig c;
  const Samples base = MakeSamples(CurvedWalk(1, 1), MakeFutureBasis(c, 12, 0.4), c, true);
  for (const double bad : {1.0, 0.0, -0.5}) {
    AugmentConfig a;
    a.speed_scales = {0.8, bad};
    try {
      Augment(base, a);
      ADD_FAILURE() << "scale " << bad << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("augment.speed_scales"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace foresight::span
