#include "datasets/occupancy_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/test_util.h"

namespace foresight {
namespace {

LaserScan Scan(double x, double y, double theta, std::vector<double> ranges, int robot = 0) {
  LaserScan s;
  s.x = x;
  s.y = y;
  s.theta = theta;
  s.robot = robot;
  s.angle_min = -M_PI / 2;
  s.angle_increment = M_PI / static_cast<double>(ranges.size());
  s.ranges = std::move(ranges);
  return s;
}

/// A few scans with varied poses and ranges in (0.2, 30) m.
std::vector<LaserScan> RandomScans(int n, int beams, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<LaserScan> scans;
  for (int s = 0; s < n; ++s) {
    std::vector<double> r(static_cast<std::size_t>(beams));
    for (double& v : r) v = 0.2 + 29.8 * u(rng);
    scans.push_back(Scan(10 * u(rng) - 5, 10 * u(rng) - 5, 2 * M_PI * u(rng), r, s % 2));
  }
  return scans;
}

TEST(OccupancyPoints, InvalidBeamsAreDroppedAndCounted) {
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  const std::vector<LaserScan> scans{Scan(0, 0, 0, {1.0, nan, -2.0, 0.0, inf, 40.0, 81.83, 39.9})};
  const LabelledPoints pts = SampleLabelledPoints(scans, {}, 3);
  EXPECT_EQ(pts.dropped_beams, 6);
  EXPECT_EQ(pts.NumOccupied(), 2);  // 1.0 m and 39.9 m
  // 1.0 m: max(1, floor(0.5)) = 1 free; 39.9 m: floor(19.95) = 19 free.
  EXPECT_EQ(pts.size(), 2 + 1 + 19);
  for (std::int64_t k = 0; k < pts.size(); ++k) EXPECT_TRUE(pts.xy.col(k).allFinite());
}

TEST(OccupancyPoints, FreeCountPerBeamFollowsTheFormula) {
  for (double r : {0.3, 1.99, 2.0, 5.5, 17.2}) {
    for (double per_metre : {0.0, 0.5, 2.0}) {
      for (int min_free : {0, 1, 3}) {
        OccupancyPointsConfig cfg;
        cfg.free_per_metre = per_metre;
        cfg.min_free_per_beam = min_free;
        const LabelledPoints pts = SampleLabelledPoints({Scan(0, 0, 0, {r})}, cfg, 1);
        const auto expected =
            std::max<std::int64_t>(min_free, static_cast<std::int64_t>(std::floor(r * per_metre)));
        EXPECT_EQ(pts.size() - pts.NumOccupied(), expected)
            << r << " " << per_metre << " " << min_free;
        EXPECT_EQ(pts.NumOccupied(), 1);
      }
    }
  }
}

TEST(OccupancyPoints, FreePointsLieOnTheBeamBeforeTheHit) {
  const std::vector<LaserScan> scans = RandomScans(5, 37, 11);
  OccupancyPointsConfig cfg;
  cfg.free_end_margin = 0.1;
  const LabelledPoints pts = SampleLabelledPoints(scans, cfg, 5);
  ASSERT_EQ(pts.num_scans(), 5);
  EXPECT_EQ(pts.scan_begin.size(), 6u);
  EXPECT_EQ(pts.scan_begin.back(), pts.size());
  EXPECT_EQ(pts.occupied.size(), static_cast<std::size_t>(pts.size()));
  double min_fraction = 1, max_fraction = 0;
  for (int s = 0; s < pts.num_scans(); ++s) {
    EXPECT_EQ(pts.robot[s], s % 2);
    const LaserScan& scan = scans[s];
    const Eigen::Vector2d origin(scan.x, scan.y);
    std::int64_t k = pts.scan_begin[s];
    for (int i = 0; i < scan.num_beams(); ++i) {  // every beam is valid: hit, then its free points
      const double r = scan.ranges[i];
      const Eigen::Vector2d dir(std::cos(scan.BeamAngle(i)), std::sin(scan.BeamAngle(i)));
      ASSERT_EQ(pts.occupied[k], 1);
      EXPECT_NEAR((pts.xy.col(k) - (origin + r * dir)).norm(), 0, 1e-9);
      ++k;
      const auto n_free = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::floor(r * 0.5)));
      for (std::int64_t j = 0; j < n_free; ++j, ++k) {
        ASSERT_EQ(pts.occupied[k], 0);
        const Eigen::Vector2d v = pts.xy.col(k) - origin;
        const double along = v.dot(dir);
        EXPECT_NEAR(std::abs(v.x() * dir.y() - v.y() * dir.x()), 0, 1e-9) << "off the beam";
        EXPECT_GE(along, 0);
        EXPECT_LE(along, r - 0.1 + 1e-12) << "not before the hit by the margin";
        min_fraction = std::min(min_fraction, along / (r - 0.1));
        max_fraction = std::max(max_fraction, along / (r - 0.1));
      }
    }
    EXPECT_EQ(k, pts.scan_begin[s + 1]);
  }
  EXPECT_LT(min_fraction, 0.02);  // uniform over the whole segment
  EXPECT_GT(max_fraction, 0.98);

  // A beam shorter than the margin puts its free points at the laser.
  const LabelledPoints tiny = SampleLabelledPoints({Scan(1, 2, 0, {0.05})}, cfg, 5);
  ASSERT_EQ(tiny.size(), 2);
  EXPECT_NEAR((tiny.xy.col(1) - Eigen::Vector2d(1, 2)).norm(), 0, 1e-15);
}

TEST(OccupancyPoints, DeterministicAndIndependentAcrossScans) {
  const std::vector<LaserScan> scans = RandomScans(12, 50, 2);
  const OccupancyPointsConfig cfg;
  const LabelledPoints a = SampleLabelledPoints(scans, cfg, 42);
  const LabelledPoints b = SampleLabelledPoints(scans, cfg, 42);
  EXPECT_EQ(a.xy, b.xy);
  EXPECT_EQ(a.occupied, b.occupied);
  EXPECT_EQ(a.scan_begin, b.scan_begin);
  const LabelledPoints other_seed = SampleLabelledPoints(scans, cfg, 43);
  ASSERT_EQ(other_seed.size(), a.size());  // counts do not depend on the seed, free points do
  EXPECT_GT((other_seed.xy - a.xy).norm(), 1.0);

  // A prefix of the log samples the same points for its scans.
  const std::vector<LaserScan> prefix(scans.begin(), scans.begin() + 5);
  const LabelledPoints p = SampleLabelledPoints(prefix, cfg, 42);
  const LabelledPoints expected = SelectScans(a, {0, 1, 2, 3, 4});
  EXPECT_EQ(p.xy, expected.xy);
  EXPECT_EQ(p.occupied, expected.occupied);
  EXPECT_EQ(p.scan_begin, expected.scan_begin);

  // Changing a later scan does not change earlier scans' points.
  std::vector<LaserScan> changed = scans;
  changed[7].ranges[3] = 1.0;
  const LabelledPoints c = SampleLabelledPoints(changed, cfg, 42);
  EXPECT_EQ(SelectScans(c, {0, 1, 2, 3, 4, 5, 6}).xy, SelectScans(a, {0, 1, 2, 3, 4, 5, 6}).xy);
  EXPECT_EQ(SelectScans(c, {8, 9, 10, 11}).xy, SelectScans(a, {8, 9, 10, 11}).xy);
}

TEST(OccupancyPoints, BadConfigAndPoseAreErrors) {
  OccupancyPointsConfig cfg;
  cfg.max_range = 0;
  testing::ExpectErrorContains([&] { SampleLabelledPoints({}, cfg, 1); }, {"max_range", "> 0"});
  cfg = {};
  cfg.min_free_per_beam = -1;
  testing::ExpectErrorContains([&] { SampleLabelledPoints({}, cfg, 1); },
                               {"min_free_per_beam", "-1"});
  const std::vector<LaserScan> scans{Scan(0, 0, 0, {1}), Scan(std::nan(""), 0, 0, {1})};
  testing::ExpectErrorContains([&] { SampleLabelledPoints(scans, {}, 1); },
                               {"scan 1", "non-finite pose"});
  const LabelledPoints empty = SampleLabelledPoints({}, {}, 1);
  EXPECT_EQ(empty.size(), 0);
  EXPECT_EQ(empty.num_scans(), 0);
  EXPECT_EQ(empty.scan_begin, std::vector<std::int64_t>{0});
}

TEST(OccupancyPoints, ConfigRoundTripsThroughYaml) {
  OccupancyPointsConfig cfg;
  cfg.free_per_metre = 1.5;
  cfg.min_free_per_beam = 2;
  const auto back =
      config::FromYaml<OccupancyPointsConfig>(config::ParseYaml(config::ToYaml(cfg), "t"), "t");
  EXPECT_EQ(back.free_per_metre, 1.5);
  EXPECT_EQ(back.min_free_per_beam, 2);
  EXPECT_EQ(back.max_range, 40.0);
  testing::ExpectErrorContains(
      [] {
        config::FromYaml<OccupancyPointsConfig>(config::ParseYaml("max_range: -1\n", "t.yaml"),
                                                "t.yaml");
      },
      {"t.yaml", "max_range"});
  EXPECT_THROW(config::FromYaml<OccupancyPointsConfig>(
                   config::ParseYaml("max_rnage: 3\n", "t.yaml"), "t.yaml"),
               Error);
}

TEST(ScanSplits, EveryKth) {
  const ScanSplit split = SplitEveryKth(910, 10, 0);
  EXPECT_EQ(split.train.size(), 819u);
  EXPECT_EQ(split.test.size(), 91u);
  EXPECT_EQ(split.test.front(), 0);
  EXPECT_EQ(split.test.back(), 900);
  EXPECT_EQ(split.train.front(), 1);
  const ScanSplit shifted = SplitEveryKth(910, 10, 9);
  EXPECT_EQ(shifted.test.size(), 91u);
  EXPECT_EQ(shifted.test.front(), 9);
  EXPECT_EQ(SplitEveryKth(905, 10, 7).test.size(), 90u);
  EXPECT_TRUE(SplitEveryKth(0, 10, 0).test.empty());
  EXPECT_EQ(SplitEveryKth(5, 1, 0).train.size(), 0u);
  testing::ExpectErrorContains([] { SplitEveryKth(10, 0, 0); }, {"test_every", "0"});
  testing::ExpectErrorContains([] { SplitEveryKth(10, 10, 10); }, {"test_offset 10"});
  testing::ExpectErrorContains([] { SplitEveryKth(10, 10, -1); }, {"test_offset -1"});
}

TEST(ScanSplits, SelectScansKeepsOrderAndRobot) {
  const std::vector<LaserScan> scans = RandomScans(6, 20, 9);
  const LabelledPoints pts = SampleLabelledPoints(scans, {}, 1);
  const LabelledPoints sel = SelectScans(pts, {4, 1, 4});
  ASSERT_EQ(sel.num_scans(), 3);
  EXPECT_EQ(sel.robot, (std::vector<int>{0, 1, 0}));
  EXPECT_EQ(sel.size(), 2 * pts.ScanSize(4) + pts.ScanSize(1));
  EXPECT_EQ(sel.xy.middleCols(sel.scan_begin[1], sel.ScanSize(1)),
            pts.xy.middleCols(pts.scan_begin[1], pts.ScanSize(1)));
  EXPECT_EQ(sel.xy.middleCols(sel.scan_begin[2], sel.ScanSize(2)),
            pts.xy.middleCols(pts.scan_begin[4], pts.ScanSize(4)));
  EXPECT_EQ(SelectScans(pts, {}).size(), 0);
  testing::ExpectErrorContains([&] { SelectScans(pts, {6}); },
                               {"SelectScans", "scan index 6", "[0, 6)"});
}

TEST(ScanSplits, QuadrantsOfMeanHitPoint) {
  // Scans whose hits centre on known points around the centre (1, 1); beams point along theta.
  auto at = [](double x, double y) {
    LaserScan s;
    s.x = x - 2;  // a single beam of 2 m along +x ends at (x, y)
    s.y = y;
    s.ranges = {2.0};
    return s;
  };
  std::vector<LaserScan> scans{at(0, 3), at(5, 2),     at(-1, -4),
                               at(2, 0), at(0.5, 1.0), at(1.0, 0.5)};
  LaserScan none = at(9, 9);
  none.ranges = {81.0};  // no hit at all
  scans.push_back(none);
  const LabelledPoints pts = SampleLabelledPoints(scans, {}, 1);
  const auto q = QuadrantSplit(pts, {0, 1, 2, 3, 4, 5, 6}, 1.0, 1.0);
  EXPECT_EQ(q[0], (std::vector<int>{0, 4}));  // upper-left; y == cy counts as upper
  EXPECT_EQ(q[1], (std::vector<int>{1}));
  EXPECT_EQ(q[2], (std::vector<int>{2}));
  EXPECT_EQ(q[3], (std::vector<int>{3, 5}));  // x == cx counts as right
  // Only the candidates are assigned; free points do not move the mean.
  const auto some = QuadrantSplit(pts, {3, 1}, 1.0, 1.0);
  EXPECT_TRUE(some[0].empty() && some[2].empty());
  EXPECT_EQ(some[1], (std::vector<int>{1}));
  EXPECT_EQ(some[3], (std::vector<int>{3}));
  testing::ExpectErrorContains([&] { QuadrantSplit(pts, {-1}, 0, 0); },
                               {"QuadrantSplit", "scan index -1"});

  // Mean of several hits: two beams ending at (-3, 2) and (1, 2) average to (-1, 2): upper-left.
  LaserScan two;
  two.angle_min = 0;
  two.angle_increment = M_PI;  // beam 0 along +x, beam 1 along -x
  two.x = -1;
  two.y = 2;
  two.ranges = {2.0, 2.0};
  const auto q2 = QuadrantSplit(SampleLabelledPoints({two}, {}, 1), {0}, 0.0, 0.0);
  EXPECT_EQ(q2[0], (std::vector<int>{0}));
}

}  // namespace
}  // namespace foresight
