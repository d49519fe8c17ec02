#include "models/span/span_data.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace foresight::span
