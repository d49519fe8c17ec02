#include "datasets/directional.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "core/von_mises.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

/// One csv row in the README convention: orientation_raw = pi/2 + atan2(y_prev - y, x_prev - x).
std::string CsvRow(double x, double y, double raw, int path) {
  char buf[200];
  std::snprintf(buf, sizeof(buf), "%.17g,%.17g,%.17g,%d\n", x, y, raw, path);
  return buf;
}
double Raw(double px, double py, double x, double y) {
  return M_PI / 2 + std::atan2(py - y, px - x);
}

void ExpectCounted(const DirectionalReadStats& s) {
  EXPECT_EQ(s.points, s.kept + s.first_points + s.dropped());
}

TEST(DirectionalGridCsv, HeadingsTimesAndFilters) {
  testing::TempDir dir;
  const std::string path = dir.File("sim.csv");
  std::string text = "x_m,y_m,orientation_raw_rad,path_id\n";
  text += CsvRow(0, 0, 0, 0);                        // path start: placeholder
  text += CsvRow(1, 0, Raw(0, 0, 1, 0), 0);          // moving +x: raw = 3 pi / 2
  text += CsvRow(1, 0, Raw(1, 0, 1, 0), 0);          // repeated way-point: standing
  text += CsvRow(1, 1, Raw(1, 0, 1, 1), 0);          // moving +y: raw = 0
  text += CsvRow(0.5, 0.5, Raw(1, 1, 0.5, 0.5), 0);  // moving -x-y
  text += CsvRow(3, 3, Raw(0.5, 0.5, 3, 3), 1);      // path start with a cross-path heading
  text += CsvRow(3, 13, Raw(3, 3, 3, 13), 1);        // 10 m jump
  text += CsvRow(2, 13, Raw(3, 13, 2, 13), 1);       // moving -x
  testing::WriteText(path, text);
  DirectionalReadStats st;
  const DirectionalSamples s = ReadDirectionalGridCsv(path, &st);
  ASSERT_EQ(s.size(), 4);
  EXPECT_EQ(st.points, 8);
  EXPECT_EQ(st.tracks, 2);
  EXPECT_EQ(st.kept, 4);
  EXPECT_EQ(st.first_points, 2);
  EXPECT_EQ(st.dropped_standing, 1);
  EXPECT_EQ(st.dropped_jump, 1);
  ExpectCounted(st);
  const double expect_theta[] = {0.0, M_PI / 2, -3 * M_PI / 4, -M_PI};
  const double expect_x[] = {1, 1, 0.5, 2}, expect_y[] = {0, 1, 0.5, 13};
  const double expect_t[] = {0.1, 0.3, 0.4, 0.2};  // row index within the path * 0.1 s
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(WrapAngle(s.theta[i] - expect_theta[i]), 0.0, 1e-12) << i;
    EXPECT_GE(s.theta[i], -M_PI);
    EXPECT_LT(s.theta[i], M_PI);
    EXPECT_DOUBLE_EQ(s.x[i], expect_x[i]);
    EXPECT_DOUBLE_EQ(s.y[i], expect_y[i]);
    EXPECT_NEAR(s.t[i], expect_t[i], 1e-12);
  }
}

TEST(DirectionalGridCsv, BadInputIsAnErrorWithFileAndLine) {
  testing::TempDir dir;
  const std::string path = dir.File("bad.csv");
  const std::string header = "x_m,y_m,orientation_raw_rad,path_id\n";
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(dir.File("missing.csv")); },
                               {"missing.csv", "cannot open"});
  testing::WriteText(path, "x,y,theta\n1,2,3\n");
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); }, {"bad.csv:1", "header"});
  testing::WriteText(path, header + "0,0,0,0\n1,0,1\n");
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); },
                               {"bad.csv:3", "4 comma-separated", "got 3"});
  testing::WriteText(path, header + "0,0,0,0\nnan,0,0,0\n");
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); },
                               {"bad.csv:3", "x_m", "not finite"});
  testing::WriteText(path, header + "0,0,0,0\n1,zero,0,0\n");
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); },
                               {"bad.csv:3", "y_m", "not a number", "zero"});
  testing::WriteText(path, header + "0,0,0,0\n1,0,0,1.5\n");
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); },
                               {"bad.csv:3", "path_id", "1.5"});
  testing::WriteText(path, header + CsvRow(0, 0, 0, 0) + CsvRow(1, 0, Raw(0, 0, 1, 0), 0) +
                               CsvRow(5, 5, 0, 1) + CsvRow(2, 0, 0, 0));
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); },
                               {"bad.csv:5", "path_id 0", "again"});
  // Heading column in another convention (the heading itself instead of heading - pi/2).
  testing::WriteText(path, header + CsvRow(0, 0, 0, 0) + CsvRow(1, 1, std::atan2(1, 1), 0));
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); },
                               {"bad.csv:3", "README convention"});
  testing::WriteText(path, header);
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); }, {"bad.csv", "no data rows"});
  testing::WriteText(path, header + CsvRow(0, 0, 0, 0) + CsvRow(0, 0, 0, 0));
  testing::ExpectErrorContains([&] { ReadDirectionalGridCsv(path); },
                               {"bad.csv", "no direction samples"});
}

/// An Edinburgh TRACK line from (x, y, frame) triples, with its Properties line.
std::string EdinburghTrack(int id, const std::vector<std::array<long long, 3>>& p) {
  std::ostringstream os;
  os << "Properties.R" << id << "=[" << p.size() << ' ' << p.front()[2] << ' ' << p.back()[2]
     << " 454.92 24.49 29.25 76.38 ];\n TRACK.R" << id << "=[";
  for (std::size_t i = 0; i < p.size(); ++i)
    os << (i ? ";" : "") << '[' << p[i][0] << ' ' << p[i][1] << ' ' << p[i][2] << ']';
  os << "];\n";
  return os.str();
}

TEST(EdinburghTracks, ConvertsPixelsFramesAndFilters) {
  testing::TempDir dir;
  const std::string path = dir.File("tracks.test.txt");
  const std::string text =
      "% Total number of trajectories in file are  3 \n\n" +
      EdinburghTrack(1, {{100, 200, 10},
                         {105, 200, 11},     // +x, 5 px/frame = 1.11 m/s
                         {110, 195, 12},     // +x +y (image y up is world +y)
                         {110, 195, 13},     // standing
                         {110, 195, 13},     // same frame twice: jump
                         {150, 195, 14},     // 40 px in a frame = 8.9 m/s: jump
                         {145, 195, 15},     // -x
                         {140, 195, 40},     // 25 frames = 2.8 s: gap
                         {140, 201, 42}}) +  // image y down: world -y
      EdinburghTrack(2, {{10, 10, 5}, {12, 10, 6}, {14, 10, 7}}) +  // short
      EdinburghTrack(3,
                     {{300, 300, 3}, {300, 290, 4}, {300, 280, 5}, {300, 270, 6}, {300, 260, 7}});
  testing::WriteText(path, text);
  DirectionalReadStats st;
  const DirectionalSamples s = ReadEdinburghTracks(path, HeadingFilter{}, &st);
  EXPECT_EQ(st.points, 17);
  EXPECT_EQ(st.tracks, 3);
  EXPECT_EQ(st.dropped_short_track, 3);
  EXPECT_EQ(st.first_points, 2);
  EXPECT_EQ(st.dropped_standing, 1);
  EXPECT_EQ(st.dropped_jump, 2);
  EXPECT_EQ(st.dropped_gap, 1);
  EXPECT_EQ(st.kept, 8);
  ExpectCounted(st);
  ASSERT_EQ(s.size(), 8);
  const double m = kEdinburghMetresPerPixel;
  // Track 1: points at frames 11, 12, 15, 42; the earliest frame of the file is 3.
  EXPECT_DOUBLE_EQ(s.x[0], 105 * m);
  EXPECT_DOUBLE_EQ(s.y[0], (479 - 200) * m);
  EXPECT_NEAR(s.t[0], (11 - 3) / 9.0, 1e-12);
  EXPECT_NEAR(s.theta[0], 0.0, 1e-12);
  EXPECT_NEAR(s.theta[1], M_PI / 4, 1e-12);
  EXPECT_NEAR(s.t[1], (12 - 3) / 9.0, 1e-12);
  EXPECT_NEAR(s.theta[2], -M_PI, 1e-12);
  EXPECT_NEAR(s.t[2], (15 - 3) / 9.0, 1e-12);
  EXPECT_NEAR(s.theta[3], -M_PI / 2, 1e-12);
  EXPECT_DOUBLE_EQ(s.y[3], (479 - 201) * m);
  // Track 3 moves up the image: +y in the world frame, starting at t = 1/9 s.
  for (int i = 4; i < 8; ++i) EXPECT_NEAR(s.theta[i], M_PI / 2, 1e-12) << i;
  EXPECT_NEAR(s.t[4], 1 / 9.0, 1e-12);
  // A looser filter keeps the fast step and the short track; the step across the (now allowed)
  // gap is 5 px in 25 frames = 0.044 m/s: standing.
  HeadingFilter loose;
  loose.max_speed = 20;
  loose.max_gap = 5;
  loose.min_track_points = 2;
  const DirectionalSamples s2 = ReadEdinburghTracks(path, loose, &st);
  EXPECT_EQ(st.dropped_jump, 1);
  EXPECT_EQ(st.dropped_gap, 0);
  EXPECT_EQ(st.dropped_standing, 2);
  EXPECT_EQ(st.dropped_short_track, 0);
  EXPECT_EQ(s2.size(), 8 + 1 + 2);
  ExpectCounted(st);
}

TEST(EdinburghTracks, BadInputIsAnErrorWithFileAndLine) {
  testing::TempDir dir;
  const std::string path = dir.File("tracks.bad.txt");
  const HeadingFilter f;
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(dir.File("none.txt"), f); },
                               {"none.txt", "cannot open"});
  testing::WriteText(path, "% header\n TRACK.R1=[[1 2 3];[4 5 6]\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt:2", "TRACK.R1", "must look like"});
  testing::WriteText(path, " TRACK.R1=[[1 2 3];[4 nan 4];[5 5 5]];\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt:1", "point 2", "non-finite"});
  testing::WriteText(path, " TRACK.R1=[[1 2 3];[4 5];[5 5 5]];\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt:1", "point 2", "x y frame"});
  testing::WriteText(path, " TRACK.R7=[[1 2 3];[4 5 2.5]];\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt:1", "TRACK.R7", "not an integer"});
  testing::WriteText(path, "\n TRACK.R1=[[1 2 3];[4 5 2]];\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt:2", "back in time", "frame 2 after 3"});
  testing::WriteText(path, "Properties.R1=[3 3 4 1.0];\n TRACK.R1=[[1 2 3];[4 5 4]];\n");
  testing::ExpectErrorContains(
      [&] { ReadEdinburghTracks(path, f); },
      {"tracks.bad.txt:2", "2 points in frames 3..4", "Properties.R1 says 3 points"});
  testing::WriteText(path, "garbage\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt:1", "expected a comment"});
  testing::WriteText(path, "% only a comment\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt", "no TRACK lines"});
  testing::WriteText(path, " TRACK.R1=[[1 2 3];[1 2 4];[1 2 5];[1 2 6];[1 2 7]];\n");
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, f); },
                               {"tracks.bad.txt", "no direction samples left"});
  HeadingFilter bad;
  bad.max_speed = -1;
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, bad); },
                               {"heading filter", "max_speed -1"});
}

// Found by review with fuzz_directional_csv (tests/fuzz/corpus/directional_csv/
// regress_frame_overflow): frame differences overflowed long long (undefined behaviour) for
// frames at both ends of its range; they are taken in double now.
TEST(EdinburghTracks, FramesAtTheEndsOfTheRangeDoNotOverflow) {
  testing::TempDir dir;
  const std::string path = dir.File("tracks.huge.txt");
  testing::WriteText(path,
                     " TRACK.R1=[[1 2 -9000000000000000000];[4 5 9000000000000000000];"
                     "[8 5 9000000000000000001];[12 5 9000000000000000002];"
                     "[16 5 9000000000000000003]];\n");
  DirectionalReadStats st;
  testing::ExpectErrorContains([&] { ReadEdinburghTracks(path, HeadingFilter{}, &st); },
                               {path, "no direction samples left"});
  // A gap that large is a gap; the track restarts after it.
  testing::WriteText(path,
                     " TRACK.R1=[[1 2 -9000000000000000000];[100 200 9000000000000000000];"
                     "[104 200 9000000000000001024];[108 200 9000000000000002048];"
                     "[112 200 9000000000000003072]];\n");
  HeadingFilter slow;
  slow.max_gap = 1e3;
  slow.min_speed = 0;
  const DirectionalSamples s = ReadEdinburghTracks(path, slow, &st);
  EXPECT_EQ(st.dropped_gap, 1);
  EXPECT_EQ(s.size(), 3);
}

TEST(DirectionalSamples, SelectAndValidate) {
  DirectionalSamples s;
  s.x = Eigen::VectorXd::LinSpaced(5, 0, 4);
  s.y = -s.x;
  s.t = 2 * s.x;
  s.theta = Eigen::VectorXd::Constant(5, 0.5);
  const DirectionalSamples sel = s.Select({4, 1});
  ASSERT_EQ(sel.size(), 2);
  EXPECT_EQ(sel.x[0], 4);
  EXPECT_EQ(sel.y[1], -1);
  EXPECT_EQ(sel.t[0], 8);
  s.Validate("ok");
  testing::ExpectErrorContains([&] { s.Select({5}); }, {"row 5", "[0, 5)"});
  DirectionalSamples bad = s;
  bad.theta[2] = M_PI;
  testing::ExpectErrorContains([&] { bad.Validate("here"); },
                               {"here", "sample 2", "outside [-pi, pi)"});
  bad = s;
  bad.y[3] = std::nan("");
  testing::ExpectErrorContains([&] { bad.Validate("here"); }, {"here", "sample 3", "not finite"});
  testing::ExpectErrorContains([&] { DirectionalSamples().Validate("empty"); },
                               {"empty", "no direction samples"});
}

TEST(CrossingFlow, DeterministicAndTheDominantDirectionFlips) {
  CrossingFlowConfig c;
  c.seed = 9;
  const DirectionalSamples a = GenerateCrossingFlow(c), b = GenerateCrossingFlow(c);
  ASSERT_GT(a.size(), 1000);
  EXPECT_EQ(a.theta, b.theta);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.t, b.t);
  c.seed = 10;
  const DirectionalSamples other = GenerateCrossingFlow(c);
  EXPECT_FALSE(other.size() == a.size() && other.x == a.x);
  a.Validate("crossing");
  EXPECT_GE(a.x.minCoeff(), 0);
  EXPECT_LE(a.x.maxCoeff(), c.size);
  EXPECT_GE(a.y.minCoeff(), 0);
  EXPECT_LE(a.y.maxCoeff(), c.size);
  EXPECT_GE(a.t.minCoeff(), 0);
  EXPECT_LE(a.t.maxCoeff(), c.duration);
  // Mean direction cosine per half (away from the switch): the dominant way is +x then -x.
  double c1 = 0, c2 = 0;
  int n1 = 0, n2 = 0;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    if (a.t[i] < 0.4 * c.duration) {
      c1 += std::cos(a.theta[i]);
      ++n1;
    }
    if (a.t[i] > 0.6 * c.duration) {
      c2 += std::cos(a.theta[i]);
      ++n2;
    }
  }
  ASSERT_GT(n1, 100);
  ASSERT_GT(n2, 100);
  EXPECT_GT(c1 / n1, 0.7);
  EXPECT_LT(c2 / n2, -0.7);
  // Every track flips with dominant_fraction = 1 in a noiseless flow: all headings point one way.
  c.dominant_fraction = 1.0;
  c.heading_noise = 0;
  const DirectionalSamples pure = GenerateCrossingFlow(c);
  for (Eigen::Index i = 0; i < pure.size(); ++i) {
    if (pure.t[i] < 0.4 * c.duration) {
      EXPECT_GT(std::cos(pure.theta[i]), 0) << i;
    }
    if (pure.t[i] > 0.6 * c.duration) {
      EXPECT_LT(std::cos(pure.theta[i]), 0) << i;
    }
  }
  c.speed = 0;
  testing::ExpectErrorContains([&] { GenerateCrossingFlow(c); }, {"crossing flow", "speed 0"});
}

TEST(KFold, PartitionsEveryRowOnceAndIsSeeded) {
  const auto folds = KFoldTestIndices(103, 10, 4);
  ASSERT_EQ(folds.size(), 10u);
  std::set<Eigen::Index> seen;
  for (const auto& f : folds) {
    EXPECT_GE(f.size(), 10u);
    EXPECT_LE(f.size(), 11u);
    EXPECT_TRUE(std::is_sorted(f.begin(), f.end()));
    for (Eigen::Index i : f) EXPECT_TRUE(seen.insert(i).second) << i;
  }
  EXPECT_EQ(seen.size(), 103u);
  EXPECT_EQ(*seen.begin(), 0);
  EXPECT_EQ(*seen.rbegin(), 102);
  EXPECT_EQ(KFoldTestIndices(103, 10, 4), folds);
  EXPECT_NE(KFoldTestIndices(103, 10, 5), folds);
  testing::ExpectErrorContains([] { KFoldTestIndices(5, 1, 0); }, {"k 1", "rows 5"});
  testing::ExpectErrorContains([] { KFoldTestIndices(3, 4, 0); }, {"k 4", "rows 3"});
}

TEST(DirectionalGridCsv, PathIdsFollowDrawnPathsAndSplitAtJumps) {
  testing::TempDir dir;
  const std::string path = dir.File("paths.csv");
  std::string text = "x_m,y_m,orientation_raw_rad,path_id\n";
  text += CsvRow(0, 0, 0, 0);                   // path start
  text += CsvRow(1, 0, Raw(0, 0, 1, 0), 0);     // id 0
  text += CsvRow(1, 1, Raw(1, 0, 1, 1), 0);     // id 0
  text += CsvRow(3, 3, 0, 1);                   // path start
  text += CsvRow(3, 4, Raw(3, 3, 3, 4), 1);     // id 1
  text += CsvRow(3, 14, Raw(3, 4, 3, 14), 1);   // jump: dropped, the rest is another walk
  text += CsvRow(2, 14, Raw(3, 14, 2, 14), 1);  // id 2
  text += CsvRow(2, 14, Raw(2, 14, 2, 14), 1);  // standing: dropped, same walk
  text += CsvRow(2, 15, Raw(2, 14, 2, 15), 1);  // id 2
  text += CsvRow(0, 0, 0, 7);                   // path start (ids need not be contiguous)
  text += CsvRow(1, 0, Raw(0, 0, 1, 0), 7);     // id 3
  testing::WriteText(path, text);
  const DirectionalSamples s = ReadDirectionalGridCsv(path);
  ASSERT_EQ(s.size(), 6);
  EXPECT_EQ(s.path, (std::vector<std::int64_t>{0, 0, 1, 2, 2, 3}));
  EXPECT_DOUBLE_EQ(s.y[3], 14);  // the first sample after the jump
}

TEST(EdinburghTracks, PathIdsFollowTracksAndRestartAfterGaps) {
  testing::TempDir dir;
  const std::string path = dir.File("tracks.paths.txt");
  const std::string text =
      EdinburghTrack(1, {{100, 200, 10},
                         {105, 200, 11},     // id 0
                         {110, 195, 12},     // id 0
                         {115, 195, 13},     // id 0
                         {120, 195, 40},     // 27 frames = 3 s: gap, the track restarts
                         {125, 195, 41},     // id 1
                         {130, 195, 42}}) +  // id 1
      EdinburghTrack(2, {{10, 10, 5}, {12, 10, 6}, {14, 10, 7}}) +  // short: no id
      EdinburghTrack(3,
                     {{300, 300, 3}, {300, 290, 4}, {300, 280, 5}, {300, 270, 6}, {300, 260, 7}});
  testing::WriteText(path, text);
  DirectionalReadStats st;
  const DirectionalSamples s = ReadEdinburghTracks(path, HeadingFilter{}, &st);
  EXPECT_EQ(st.dropped_gap, 1);
  ASSERT_EQ(s.size(), 9);
  EXPECT_EQ(s.path, (std::vector<std::int64_t>{0, 0, 0, 1, 1, 2, 2, 2, 2}));
  s.Validate("edinburgh");
}

TEST(CrossingFlow, PathIsTheTrackIndex) {
  CrossingFlowConfig c;
  c.num_tracks = 40;
  c.seed = 3;
  const DirectionalSamples s = GenerateCrossingFlow(c);
  ASSERT_EQ(s.path.size(), static_cast<std::size_t>(s.size()));
  EXPECT_TRUE(std::is_sorted(s.path.begin(), s.path.end()));
  EXPECT_GE(s.path.front(), 0);
  EXPECT_LT(s.path.back(), c.num_tracks);
  // Consecutive samples of one track are one step (speed * period) and one period apart; a new
  // track starts at an edge (x within one step of 0 or size).
  const double step = c.speed * c.sample_period;
  for (Eigen::Index i = 0; i < s.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (i > 0 && s.path[k] == s.path[k - 1]) {
      EXPECT_NEAR(std::hypot(s.x[i] - s.x[i - 1], s.y[i] - s.y[i - 1]), step, 1e-9) << i;
      EXPECT_NEAR(s.t[i] - s.t[i - 1], c.sample_period, 1e-9) << i;
    } else {
      EXPECT_TRUE(s.x[i] <= step + 1e-9 || s.x[i] >= c.size - step - 1e-9) << i;
    }
  }
}

TEST(DirectionalSamples, SelectCarriesPathsAndValidateChecksTheirSize) {
  DirectionalSamples s;
  s.x = Eigen::VectorXd::LinSpaced(4, 0, 3);
  s.y = s.x;
  s.t = s.x;
  s.theta = Eigen::VectorXd::Zero(4);
  s.Validate("no paths");  // empty: allowed
  EXPECT_TRUE(s.Select({2, 0}).path.empty());
  s.path = {10, 11, 12, 13};
  s.Validate("paths");
  EXPECT_EQ(s.Select({3, 1, 1}).path, (std::vector<std::int64_t>{13, 11, 11}));
  s.path = {10, 11};
  testing::ExpectErrorContains([&] { s.Validate("here"); },
                               {"here", "path ids [2]", "empty or one per sample [4]"});
}

/// Checks that `folds` partition rows 0..n-1, are sorted and keep every group in one fold.
void ExpectGroupedPartition(const std::vector<std::vector<Eigen::Index>>& folds,
                            const std::vector<std::int64_t>& groups) {
  std::vector<int> fold_of(groups.size(), -1);
  for (std::size_t f = 0; f < folds.size(); ++f) {
    EXPECT_TRUE(std::is_sorted(folds[f].begin(), folds[f].end())) << f;
    for (Eigen::Index i : folds[f]) {
      ASSERT_GE(i, 0);
      ASSERT_LT(static_cast<std::size_t>(i), groups.size());
      EXPECT_EQ(fold_of[static_cast<std::size_t>(i)], -1) << "row " << i << " in two folds";
      fold_of[static_cast<std::size_t>(i)] = static_cast<int>(f);
    }
  }
  std::map<std::int64_t, int> fold_of_group;
  for (std::size_t i = 0; i < groups.size(); ++i) {
    EXPECT_NE(fold_of[i], -1) << "row " << i << " in no fold";
    const auto [it, fresh] = fold_of_group.emplace(groups[i], fold_of[i]);
    if (!fresh) {
      EXPECT_EQ(it->second, fold_of[i]) << "group " << groups[i] << " split";
    }
  }
}

TEST(GroupedKFold, KeepsGroupsWholeCoversEveryRowOnceAndBalances) {
  // 60 groups of 1..12 rows, rows of a group interleaved with other groups.
  std::mt19937_64 rng(7);
  std::vector<std::int64_t> groups;
  std::map<std::int64_t, std::size_t> size_of;
  for (std::int64_t g = 0; g < 60; ++g) {
    const std::size_t m = 1 + rng() % 12;
    size_of[g * 3 + 100] = m;
    for (std::size_t j = 0; j < m; ++j) groups.push_back(g * 3 + 100);
  }
  for (std::size_t i = groups.size() - 1; i > 0; --i) std::swap(groups[i], groups[rng() % (i + 1)]);
  const auto folds = GroupedKFoldTestIndices(groups, 10, 4);
  ASSERT_EQ(folds.size(), 10u);
  ExpectGroupedPartition(folds, groups);
  std::size_t lo = groups.size(), hi = 0, largest = 0;
  for (const auto& f : folds) {
    lo = std::min(lo, f.size());
    hi = std::max(hi, f.size());
  }
  for (const auto& [g, m] : size_of) largest = std::max(largest, m);
  EXPECT_LE(hi - lo, largest);  // greedy largest-first bound
  EXPECT_EQ(GroupedKFoldTestIndices(groups, 10, 4), folds);
  EXPECT_NE(GroupedKFoldTestIndices(groups, 10, 5), folds);
  // Equal groups: k divides their number -> equal folds.
  std::vector<std::int64_t> equal;
  for (int g = 0; g < 12; ++g)
    for (int j = 0; j < 5; ++j) equal.push_back(g);
  for (const auto& f : GroupedKFoldTestIndices(equal, 4, 1)) EXPECT_EQ(f.size(), 15u);
}

TEST(GroupedKFold, LargestFirstToTheSmallestFoldByHand) {
  // Sizes 5, 4, 3, 3, 2, 1 into 2 folds: 5 -> A; 4 -> B; 3 -> B (7); 3 -> A (8); 2 -> B (9);
  // 1 -> A (9). The groups of each size are unique here except the two 3s, so the fold contents
  // are fixed up to which 3-group goes where: {5, 3, 1} and {4, 3, 2}, sizes 9 and 9.
  std::vector<std::int64_t> groups;
  const int sizes[] = {5, 4, 3, 3, 2, 1};
  for (int g = 0; g < 6; ++g)
    for (int j = 0; j < sizes[g]; ++j) groups.push_back(g);
  for (std::uint64_t seed = 0; seed < 5; ++seed) {
    const auto folds = GroupedKFoldTestIndices(groups, 2, seed);
    ExpectGroupedPartition(folds, groups);
    ASSERT_EQ(folds.size(), 2u);
    EXPECT_EQ(folds[0].size(), 9u);
    EXPECT_EQ(folds[1].size(), 9u);
    // Fold 0 holds the largest group (rows 0..4) and the single row (17); fold 1 the 4-group.
    EXPECT_EQ(folds[0].front(), 0);
    EXPECT_EQ(folds[0].back(), 17);
    EXPECT_EQ(folds[1].front(), 5);
  }
  testing::ExpectErrorContains(
      [] {
        GroupedKFoldTestIndices({1, 1, 2, 2}, 3, 0);
      },
      {"k 3", "groups 2"});
  testing::ExpectErrorContains(
      [] {
        GroupedKFoldTestIndices({1, 2, 3}, 1, 0);
      },
      {"k 1", "groups 3"});
  testing::ExpectErrorContains([] { GroupedKFoldTestIndices({}, 2, 0); }, {"k 2", "groups 0"});
}

/// A real data file under $FORESIGHT_DATA or ../shared/data, or "" when absent.
std::string RealFile(const std::string& relative) {
  std::vector<std::filesystem::path> roots;
  if (const char* data = std::getenv("FORESIGHT_DATA")) roots.emplace_back(data);
  if (const std::string shared = testing::SharedDataDir(); !shared.empty())
    roots.emplace_back(shared);
  for (const auto& root : roots)
    if (std::filesystem::exists(root / relative)) return (root / relative).string();
  return "";
}

TEST(DirectionalGridCsv, RealFilesWhenPresent) {
  for (const std::string name : {"unimodal_sim1.csv", "multimodal_sim2.csv"}) {
    const std::string path = RealFile("directional_grid_maps_sim/" + name);
    if (path.empty())
      GTEST_SKIP() << "directional_grid_maps_sim/" << name
                   << " not found under $FORESIGHT_DATA or ../shared/data";
    DirectionalReadStats st;
    const DirectionalSamples s = ReadDirectionalGridCsv(path, &st);
    ExpectCounted(st);
    // README: 3,133 and 6,435 rows in 12 and 23 paths; extent x in [1.03, 18.5], y in [-3.9, 28.2].
    EXPECT_EQ(st.points, name[0] == 'u' ? 3133 : 6435);
    EXPECT_EQ(st.tracks, name[0] == 'u' ? 12 : 23);
    EXPECT_GT(st.kept, 0.9 * st.points);
    EXPECT_GE(s.x.minCoeff(), 1.0);
    EXPECT_LE(s.x.maxCoeff(), 18.6);
    EXPECT_GE(s.y.minCoeff(), -4.0);
    EXPECT_LE(s.y.maxCoeff(), 28.3);
  }
}

TEST(EdinburghTracks, RealFilesWhenPresent) {
  for (const std::string name : {"tracks.01Aug.txt", "tracks.01Jul.txt"}) {
    const std::string path = RealFile("edinburgh_forum/" + name);
    if (path.empty())
      GTEST_SKIP() << "edinburgh_forum/" << name
                   << " not found under $FORESIGHT_DATA or ../shared/data";
    DirectionalReadStats st;
    const DirectionalSamples s = ReadEdinburghTracks(path, HeadingFilter{}, &st);
    ExpectCounted(st);
    // README: 146 / 1,262 trajectories with 22,195 / 111,230 points in a 640 x 480 image.
    EXPECT_EQ(st.tracks, name == "tracks.01Aug.txt" ? 146 : 1262);
    EXPECT_EQ(st.points, name == "tracks.01Aug.txt" ? 22195 : 111230);
    EXPECT_GT(st.kept, st.points / 2);
    EXPECT_GE(s.x.minCoeff(), 0);
    EXPECT_LE(s.x.maxCoeff(), 640 * kEdinburghMetresPerPixel);
    EXPECT_GE(s.y.minCoeff(), 0);
    EXPECT_LE(s.y.maxCoeff(), 480 * kEdinburghMetresPerPixel);
    EXPECT_GE(s.t.minCoeff(), 0);
  }
}

}  // namespace
}  // namespace foresight
