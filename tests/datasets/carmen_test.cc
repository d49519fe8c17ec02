#include "datasets/carmen.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "datasets/occupancy_points.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

/// A FLASER line with `ranges`, laser pose (x, y, theta) and time t; odometry repeats the pose.
std::string Flaser(const std::vector<std::string>& ranges, const std::string& x,
                   const std::string& y, const std::string& theta, const std::string& t = "12.5") {
  std::ostringstream os;
  os << "FLASER " << ranges.size();
  for (const auto& r : ranges) os << ' ' << r;
  os << ' ' << x << ' ' << y << ' ' << theta << ' ' << x << ' ' << y << ' ' << theta << ' ' << t
     << " pippo " << t << '\n';
  return os.str();
}

std::vector<std::string> Ranges(int n, const std::string& value) {
  return std::vector<std::string>(n, value);
}

TEST(Carmen, ReadsFlaserOnlyWithPoseTimeAndBeamGeometry) {
  testing::TempDir dir;
  const std::string path = dir.File("log.txt");
  testing::WriteText(path,
                     "# a comment\n\nPARAM robot_frontlaser_offset 0.0\n"
                     "ODOM 0 0 0 0 0 0 0.1 pippo 0.1\n" +
                         Flaser(Ranges(180, "2.5"), "1.0", "-2.0", "0.5", "3.25") + "NEFF 30.2\n" +
                         Flaser(Ranges(180, "81.83"), "0", "0", "0", "3.5"));
  const std::vector<LaserScan> scans = ReadCarmenLog(path);
  ASSERT_EQ(scans.size(), 2u);
  const LaserScan& s = scans[0];
  EXPECT_DOUBLE_EQ(s.time, 3.25);
  EXPECT_EQ(s.robot, 0);
  EXPECT_DOUBLE_EQ(s.x, 1.0);
  EXPECT_DOUBLE_EQ(s.y, -2.0);
  EXPECT_DOUBLE_EQ(s.theta, 0.5);
  ASSERT_EQ(s.ranges.size(), 180u);
  EXPECT_DOUBLE_EQ(s.ranges[7], 2.5);
  // README convention: beam i at theta - pi/2 + i * pi/180.
  EXPECT_NEAR(s.BeamAngle(0), 0.5 - M_PI / 2, 1e-12);
  EXPECT_NEAR(s.BeamAngle(90), 0.5, 1e-12);
  EXPECT_NEAR(s.BeamAngle(179), 0.5 + M_PI / 2 - M_PI / 180, 1e-12);
  EXPECT_DOUBLE_EQ(scans[1].ranges[0], 81.83);
  EXPECT_DOUBLE_EQ(scans[1].time, 3.5);
}

TEST(Carmen, BeamEndPointFollowsTheAngleConvention) {
  // Laser at (2, 1) heading +y (theta = pi/2); beam 0 points along +x (theta - pi/2), beam 90
  // along +y, beam 45 at 45 degrees. One beam of 3 m each; others are no return.
  testing::TempDir dir;
  const std::string path = dir.File("one.log");
  for (int beam : {0, 45, 90, 179}) {
    std::vector<std::string> r = Ranges(180, "81.83");
    r[beam] = "3";
    testing::WriteText(path, Flaser(r, "2", "1", "1.5707963267948966"));
    const std::vector<LaserScan> scans = ReadCarmenLog(path);
    OccupancyPointsConfig cfg;
    const LabelledPoints pts = SampleLabelledPoints(scans, cfg, 1);
    ASSERT_EQ(pts.NumOccupied(), 1) << beam;
    ASSERT_EQ(pts.occupied[0], 1);
    const double world = M_PI / 2 - M_PI / 2 + beam * M_PI / 180;
    EXPECT_NEAR(pts.xy(0, 0), 2 + 3 * std::cos(world), 1e-9) << beam;
    EXPECT_NEAR(pts.xy(1, 0), 1 + 3 * std::sin(world), 1e-9) << beam;
    EXPECT_EQ(pts.dropped_beams, 179);
  }
  // Spot values: beam 0 ends at (5, 1), beam 90 at (2, 4).
  std::vector<std::string> r = Ranges(180, "81.83");
  r[0] = "3";
  r[90] = "3";
  testing::WriteText(path, Flaser(r, "2", "1", "1.5707963267948966"));
  const LabelledPoints pts = SampleLabelledPoints(ReadCarmenLog(path), {}, 1);
  std::vector<Eigen::Vector2d> hits;
  for (std::int64_t k = 0; k < pts.size(); ++k)
    if (pts.occupied[k]) hits.push_back(pts.xy.col(k));
  ASSERT_EQ(hits.size(), 2u);
  EXPECT_NEAR((hits[0] - Eigen::Vector2d(5, 1)).norm(), 0, 1e-9);
  EXPECT_NEAR((hits[1] - Eigen::Vector2d(2, 4)).norm(), 0, 1e-9);
}

TEST(Carmen, KeepsNanAndNegativeRanges) {
  testing::TempDir dir;
  const std::string path = dir.File("odd.log");
  std::vector<std::string> r = Ranges(4, "1.0");
  r[1] = "nan";
  r[2] = "-1";
  r[3] = "inf";
  testing::WriteText(path, Flaser(r, "0", "0", "0"));
  const std::vector<LaserScan> scans = ReadCarmenLog(path);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_TRUE(std::isnan(scans[0].ranges[1]));
  EXPECT_DOUBLE_EQ(scans[0].ranges[2], -1.0);
  EXPECT_TRUE(std::isinf(scans[0].ranges[3]));
  EXPECT_NEAR(scans[0].angle_increment, M_PI / 4, 1e-15);  // n beams over 180 degrees
}

TEST(Carmen, MalformedInputNamesFileLineAndField) {
  testing::TempDir dir;
  auto check = [&](const std::string& text, std::vector<std::string> parts,
                   const CarmenReadOptions& options = {}) {
    const std::string path = dir.File("bad.log");
    testing::WriteText(path, text);
    parts.insert(parts.begin(), path);
    testing::ExpectErrorContains([&] { ReadCarmenLog(path, options); }, parts);
  };
  const std::string good = Flaser(Ranges(3, "1"), "0", "0", "0");
  testing::ExpectErrorContains([] { ReadCarmenLog("/nonexistent/intel.log"); },
                               {"/nonexistent/intel.log", "cannot open"});
  check("", {"no FLASER messages"});
  check("# only a comment\nODOM 0 0 0 0 0 0 0.1 pippo 0.1\n", {"no FLASER messages"});
  // Truncated: the last field (logger_timestamp) is missing.
  std::string truncated = good;
  truncated.resize(truncated.rfind(' '));
  check(good + truncated + "\n", {":2:", "needs 14 fields", "got 13"});
  check("FLASER 180 1 2 3\n", {":1:", "180 beams", "needs 191 fields", "got 5"});
  check(good + good + "FLASER\n", {":3:", "without a beam count"});
  check("FLASER abc 1 2\n", {":1:", "beam count", "'abc'"});
  check("FLASER 9223372036854775807 1 2\n", {":1:", "implausible"});
  check("FLASER -3 1 2\n", {":1:", "not a positive integer", "'-3'"});
  check(Flaser({"1", "x1", "1"}, "0", "0", "0"),
        {":1:", "field 4", "range 1", "not a number", "'x1'"});
  check(Flaser(Ranges(3, "1"), "0", "abc", "0"), {":1:", "(y)", "'abc'"});
  check(Flaser(Ranges(3, "1"), "0", "0", "0", "t0"), {":1:", "ipc_timestamp", "'t0'"});
  check(good + Flaser(Ranges(3, "1"), "nan", "0", "0"), {":2:", "(x)", "not finite"});
  check(Flaser(Ranges(3, "1"), "0", "0", "inf"), {":1:", "(theta)", "not finite"});
  check(Flaser(Ranges(3, "1"), "0", "0", "0", "nan"), {":1:", "ipc_timestamp", "not finite"});
  check("ODOM 0 0 0 0 0 0 0.1 pippo 0.1\n" + good + Flaser(Ranges(4, "1"), "0", "0", "0"),
        {":3:", "4 beams", "first scan (line 2) has 3"});
  // Without the constant-count requirement both scans load.
  const std::string path = dir.File("mixed.log");
  testing::WriteText(path, good + Flaser(Ranges(4, "1"), "0", "0", "0"));
  CarmenReadOptions lenient;
  lenient.require_constant_beam_count = false;
  const auto scans = ReadCarmenLog(path, lenient);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[1].ranges.size(), 4u);
  EXPECT_NEAR(scans[1].angle_increment, M_PI / 4, 1e-15);
}

/// ../shared/data/intel_lab/intel.gfs.log ($FORESIGHT_DATA first), or "" when absent.
std::string IntelLogPath() {
  std::vector<std::filesystem::path> roots;
  if (const char* data = std::getenv("FORESIGHT_DATA")) roots.emplace_back(data);
  if (const std::string shared = testing::SharedDataDir(); !shared.empty())
    roots.emplace_back(shared);
  for (const auto& root : roots) {
    const auto file = root / "intel_lab" / "intel.gfs.log";
    if (std::filesystem::exists(file)) return file.string();
  }
  return "";
}

TEST(Carmen, RealIntelLogWhenPresent) {
  const std::string path = IntelLogPath();
  if (path.empty())
    GTEST_SKIP() << "intel_lab/intel.gfs.log not found under $FORESIGHT_DATA or ../shared/data";
  const std::vector<LaserScan> scans = ReadCarmenLog(path);
  ASSERT_EQ(scans.size(), 910u);
  double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
  int time_decreases = 0;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    ASSERT_EQ(scans[s].ranges.size(), 180u);
    if (s > 0 && scans[s].time < scans[s - 1].time) {
      ++time_decreases;  // the file's ipc_timestamps step back a little 4 times (scans kept in file
                         // order)
      EXPECT_GT(scans[s].time, scans[s - 1].time - 1.0) << "scan " << s;
    }
    min_x = std::min(min_x, scans[s].x), max_x = std::max(max_x, scans[s].x);
    min_y = std::min(min_y, scans[s].y), max_y = std::max(max_y, scans[s].y);
  }
  EXPECT_NEAR(scans[0].time, 32.9068, 1e-9);
  EXPECT_NEAR(scans[0].x, 0.600266, 1e-12);
  EXPECT_NEAR(scans[0].theta, -0.354665, 1e-12);
  // README: robot poses span x in [-9.2, 16.5], y in [-22.1, 3.9].
  EXPECT_NEAR(min_x, -9.2, 0.1);
  EXPECT_NEAR(max_x, 16.5, 0.1);
  EXPECT_NEAR(min_y, -22.1, 0.1);
  EXPECT_NEAR(max_y, 3.9, 0.1);
  EXPECT_EQ(time_decreases, 4);
  EXPECT_NEAR(scans.back().time, 2683.77, 1e-9);

  // 0.5 free points per metre, at least one per beam, 40 m cut-off: each kept beam of range d
  // gives 1 + max(1, floor(d / 2)) points. These counts do not depend on the seed.
  const OccupancyPointsConfig cfg;
  const LabelledPoints pts = SampleLabelledPoints(scans, cfg, 7);
  const std::int64_t hits = pts.NumOccupied();
  EXPECT_EQ(pts.num_scans(), 910);
  EXPECT_EQ(hits, 159628);
  EXPECT_EQ(pts.dropped_beams, 4172);  // 2.5 % of 163,800 readings are >= 80 m
  EXPECT_EQ(hits + pts.dropped_beams, 910 * 180);
  EXPECT_EQ(pts.size() - hits, 223491);
  EXPECT_EQ(pts.size(), 383119);
  // README: "about 0.5 free points per metre with a 40 m cut-off gives 386,762 rows"; the BHM
  // repository's intel.csv has 383,118 rows and first scans of 380, 388, 390, 414 rows.
  EXPECT_NEAR(static_cast<double>(pts.size()), 386762.0, 0.01 * 386762.0);
  EXPECT_EQ(pts.ScanSize(1), 388);
  EXPECT_EQ(pts.ScanSize(2), 390);
  EXPECT_EQ(pts.ScanSize(3), 414);

  // The thesis 9:1 scan split.
  const ScanSplit split = SplitEveryKth(pts.num_scans(), 10, 0);
  EXPECT_EQ(split.train.size(), 819u);
  EXPECT_EQ(split.test.size(), 91u);
  const LabelledPoints train = SelectScans(pts, split.train), test = SelectScans(pts, split.test);
  EXPECT_EQ(train.size() + test.size(), pts.size());
  EXPECT_EQ(train.size(), 345061);
  // Every hit lies within the README's extent of hit points.
  for (std::int64_t k = 0; k < pts.size(); ++k) {
    if (!pts.occupied[k]) continue;
    ASSERT_TRUE(pts.xy(0, k) > -20.5 && pts.xy(0, k) < 19.5 && pts.xy(1, k) > -24 &&
                pts.xy(1, k) < 13.5)
        << pts.xy.col(k).transpose();
  }
}

}  // namespace
}  // namespace foresight
