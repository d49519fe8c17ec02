// The LASA reader on the shipped CSV export (skipped when ../shared/data is absent): shape list,
// sizes, goals, and the recorded velocities against finite differences of the positions; and on
// malformed files written here, each error naming the file and the line.

#include "datasets/lasa.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>

#include "tests/test_util.h"

namespace foresight {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::TempDir;
using foresight::testing::WriteText;

/// ../shared/data/lasa_handwriting, or "" when absent.
std::string LasaDir() {
  const std::string data = foresight::testing::SharedDataDir();
  if (data.empty()) return "";
  const std::string dir = data + "/lasa_handwriting";
  return std::filesystem::is_directory(dir + "/csv") ? dir : "";
}

#define SKIP_WITHOUT_LASA(dir)                                                           \
  const std::string dir = LasaDir();                                                     \
  if (dir.empty())                                                                       \
  GTEST_SKIP() << "../shared/data/lasa_handwriting is absent (set FORESIGHT_SOURCE_DIR " \
                  "to the repository root next to shared/): skipping the real LASA data"

TEST(Lasa, ListsTheShippedShapes) {
  SKIP_WITHOUT_LASA(dir);
  const std::vector<std::string> shapes = ListLasaShapes(dir);
  ASSERT_EQ(shapes.size(), 24u);
  EXPECT_EQ(shapes.front(), "Angle");
  EXPECT_EQ(shapes.back(), "Zshape");
  EXPECT_TRUE(std::is_sorted(shapes.begin(), shapes.end()));
  EXPECT_NE(std::find(shapes.begin(), shapes.end(), "Sshape"), shapes.end());
  EXPECT_NE(std::find(shapes.begin(), shapes.end(), "Multi_Models_4"), shapes.end());
}

TEST(Lasa, SshapeHasSevenDemosEndingAtTheOrigin) {
  SKIP_WITHOUT_LASA(dir);
  const DemoSet set = ReadLasaShape(dir, "Sshape");
  EXPECT_EQ(set.name, "Sshape");
  EXPECT_EQ(set.dimension, 2);
  ASSERT_EQ(set.demos.size(), 7u);
  for (std::size_t i = 0; i < set.demos.size(); ++i) {
    const Demonstration& d = set.demos[i];
    ASSERT_EQ(d.points(), 1000) << "demo " << i;
    EXPECT_LT(d.position.col(999).norm(), 1e-6) << "demo " << i;
    EXPECT_TRUE(d.velocity.allFinite()) << "demo " << i;
    EXPECT_EQ(d.time(0), 0.0);
    // The recorded velocities are the positions' derivative: compare with central differences
    // in the middle of the demo (relative to the typical speed).
    const double speed = d.velocity.colwise().norm().mean();
    double worst = 0;
    for (int j = 100; j < 900; ++j) {
      const Eigen::Vector2d fd =
          (d.position.col(j + 1) - d.position.col(j - 1)) / (d.time(j + 1) - d.time(j - 1));
      worst = std::max(worst, (fd - d.velocity.col(j)).norm());
    }
    EXPECT_LT(worst, 0.1 * speed) << "demo " << i;
  }
  const GoalSpread spread = CheckDemonstrations(set, 1e-9);
  EXPECT_LT(spread.goal.norm(), 1e-6);
  EXPECT_GT(spread.extent, 20.0);  // tablet units, roughly +-50
}

TEST(Lasa, EveryShapeReadsAndConverges) {
  SKIP_WITHOUT_LASA(dir);
  const auto start = std::chrono::steady_clock::now();
  for (const std::string& shape : ListLasaShapes(dir)) {
    const DemoSet set = ReadLasaShape(dir, shape);
    EXPECT_EQ(set.demos.size(), 7u) << shape;
    EXPECT_NO_THROW(CheckDemonstrations(set, 1e-6)) << shape;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 5.0) << "reading 24 shapes took " << seconds << " s";
}

class LasaMalformed : public ::testing::Test {
 protected:
  /// Writes csv/Bad.csv with `text`; returns its path.
  std::string Write(const std::string& text) {
    std::filesystem::create_directories(tmp_.path() + "/csv");
    const std::string path = tmp_.path() + "/csv/Bad.csv";
    WriteText(path, text);
    return path;
  }
  DemoSet Read() { return ReadLasaShape(tmp_.path(), "Bad"); }
  TempDir tmp_;
};

const char kHead[] = "demo,t,x,y,vx,vy,ax,ay\n";
const char kRow0[] = "0,0,1,2,0.1,0.2,0,0\n0,0.1,1.5,2.5,0.1,0.2,0,0\n0,0.2,0,0,0,0,0,0\n";

TEST_F(LasaMalformed, AcceptsDemosOfDifferentLengths) {
  Write(std::string(kHead) + kRow0 + "1,0,3,4,0,0,0,0\n1,0.05,2,2,0,0,0,0\n1,0.1,1,1,0,0,0,0\r\n" +
        "1,0.15,0,0,0,0,0,0\n");
  const DemoSet set = Read();
  ASSERT_EQ(set.demos.size(), 2u);
  EXPECT_EQ(set.demos[0].points(), 3);
  EXPECT_EQ(set.demos[1].points(), 4);
  EXPECT_EQ(set.demos[1].position.col(0), Eigen::Vector2d(3, 4));
  EXPECT_EQ(set.demos[0].velocity.col(1), Eigen::Vector2d(0.1, 0.2));
  EXPECT_DOUBLE_EQ(set.demos[1].time(3), 0.15);
  EXPECT_NO_THROW(CheckDemonstrations(set, 0));
}

TEST_F(LasaMalformed, ErrorsNameFileAndLine) {
  std::string path = Write("demo,t,x,y,vx,vy\n" + std::string(kRow0));
  ExpectErrorContains([&] { Read(); }, {path + ":1:", "header", "demo,t,x,y,vx,vy,ax,ay"});
  path = Write(std::string(kHead) + "0,0,1,2,0.1,0.2,0,0\n0,0.1,abc,2.5,0.1,0.2,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":3:", "column 'x'", "not a number", "abc"});
  path = Write(std::string(kHead) + "0,0,1,2,0.1,0.2,0,0\n0,0.1,1,nan,0.1,0.2,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":3:", "column 'y'", "not finite"});
  path = Write(std::string(kHead) + "0,0,1,2,0.1,0.2,0,0\n0,0.1,1,2,0.1,0.2,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":3:", "7 fields, expected 8"});
  path = Write(std::string(kHead) + "0,0,1,2,0.1,0.2,0,0,9\n");
  ExpectErrorContains([&] { Read(); }, {path + ":2:", "more than 8 fields"});
  path = Write(std::string(kHead) + kRow0 + "1,0,1,2,0,0,0,0\n0,0.3,1,2,0,0,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":6:", "demo index 0 out of order", "after demo 1"});
  path = Write(std::string(kHead) + kRow0 + "2,0,1,2,0,0,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":5:", "demo index 2 out of order"});
  path = Write(std::string(kHead) + "1,0,1,2,0,0,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":2:", "first row must be demo 0"});
  path = Write(std::string(kHead) + "0.5,0,1,2,0,0,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":2:", "demo index is not a non-negative integer"});
  // Found with fuzz_lasa (tests/fuzz/corpus/lasa/regress_huge_demo_index): a huge demo index
  // overflowed the conversion to size_t (undefined behaviour).
  path = Write(std::string(kHead) + kRow0 + "1e300,0.1,0,0,0,0,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":5:", "demo index", "1e+300", "at most 2^53"});
  path = Write(std::string(kHead) + "0,0,1,2,0,0,0,0\n0,0,1,2,0,0,0,0\n");
  ExpectErrorContains([&] { Read(); }, {path + ":3:", "time 0 does not increase within demo 0"});
  path = Write(kHead);
  ExpectErrorContains([&] { Read(); }, {path, "no data rows"});
  path = Write("");
  ExpectErrorContains([&] { Read(); }, {path + ":1:", "empty file"});
  ExpectErrorContains([&] { ReadLasaShape(tmp_.path(), "Missing"); },
                      {"Missing.csv", "cannot open", "'Missing'"});
}

TEST_F(LasaMalformed, ListingAnEmptyOrMissingDirectory) {
  ExpectErrorContains([&] { ListLasaShapes(tmp_.path()); },
                      {tmp_.path() + "/csv", "not a directory"});
  std::filesystem::create_directories(tmp_.path() + "/csv");
  WriteText(tmp_.path() + "/csv/notes.txt", "not a shape");
  ExpectErrorContains([&] { ListLasaShapes(tmp_.path()); }, {"no .csv file", tmp_.path() + "/csv"});
  Write(std::string(kHead) + kRow0);
  EXPECT_EQ(ListLasaShapes(tmp_.path()), std::vector<std::string>{"Bad"});
}

}  // namespace
}  // namespace foresight
