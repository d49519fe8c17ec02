// MotionBenchMaker loaders: the real problems (skipped without ../shared/data), YAML and compact
// JSON agreement, goals matched by joint name, and small broken files in a temp dir.

#include "inference/manipulation/mbm_problem.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

namespace fs = std::filesystem;
using testing::ExpectErrorContains;
using testing::TempDir;
using testing::WriteText;

/// ../shared/data/motionbenchmaker_panda, or "" when absent.
std::string MbmDir() {
  const std::string data = testing::SharedDataDir();
  if (data.empty()) return "";
  const fs::path dir = fs::path(data) / "motionbenchmaker_panda";
  return fs::is_directory(dir / "problems") ? dir.string() : "";
}

#define SKIP_WITHOUT_MBM(dir)                                                                    \
  const std::string dir = MbmDir();                                                              \
  if (dir.empty())                                                                               \
    GTEST_SKIP() << "../shared/data/motionbenchmaker_panda is absent (set FORESIGHT_SOURCE_DIR " \
                    "to the repository root): skipping the real MBM problems";

const std::map<std::string, int> kObjectsPerFamily = {{"bookshelf_small_panda", 7},
                                                      {"box_panda", 7},
                                                      {"cage_panda", 8},
                                                      {"table_pick_panda", 12},
                                                      {"table_under_pick_panda", 12},
                                                      {"bookshelf_tall_panda", 15},
                                                      {"bookshelf_thin_panda", 21}};

/// Same obstacles (ids, types, poses, sizes: exactly), same start and goal.
void ExpectSameProblem(const ManipulationProblem& a, const ManipulationProblem& b) {
  EXPECT_EQ(a.family, b.family);
  EXPECT_EQ(a.index, b.index);
  EXPECT_EQ(a.start, b.start) << a.source << " vs " << b.source;
  EXPECT_EQ(a.goal, b.goal) << a.source << " vs " << b.source;
  ASSERT_EQ(a.world.num_obstacles(), b.world.num_obstacles());
  for (int i = 0; i < a.world.num_obstacles(); ++i) {
    const Obstacle& oa = a.world.obstacle(i);
    const Obstacle& ob = b.world.obstacle(i);
    EXPECT_EQ(oa.id, ob.id);
    ASSERT_EQ(oa.is_box(), ob.is_box()) << oa.id;
    if (oa.is_box()) {
      EXPECT_EQ(oa.box().X_WB.matrix(), ob.box().X_WB.matrix()) << oa.id;
      EXPECT_EQ(oa.box().half_size, ob.box().half_size) << oa.id;
    } else {
      EXPECT_EQ(oa.cylinder().X_WC.matrix(), ob.cylinder().X_WC.matrix()) << oa.id;
      EXPECT_EQ(oa.cylinder().radius, ob.cylinder().radius) << oa.id;
      EXPECT_EQ(oa.cylinder().half_height, ob.cylinder().half_height) << oa.id;
    }
  }
}

// ---- the real problems ----------------------------------------------------------------------

TEST(MbmProblems, ObjectCountsPerFamilyAsDocumented) {
  SKIP_WITHOUT_MBM(dir);
  for (const auto& [family, count] : kObjectsPerFamily) {
    const std::vector<ManipulationProblem> problems =
        LoadCompactFamily(dir + "/compact_json/" + family + ".json", 1, 75);
    ASSERT_EQ(problems.size(), 75u) << family;
    for (const ManipulationProblem& p : problems) {
      EXPECT_EQ(p.family, family);
      EXPECT_EQ(p.world.num_obstacles(), count) << p.source;
      EXPECT_EQ(p.start.size(), kDof);
    }
    EXPECT_EQ(problems.front().index, 1);
    EXPECT_EQ(problems.back().index, 75);
    const ManipulationProblem yaml = LoadMbmFamily(dir + "/problems", family, 75, 75).front();
    EXPECT_EQ(yaml.world.num_obstacles(), count) << yaml.source;
  }
}

TEST(MbmProblems, YamlAndCompactJsonAgree) {
  SKIP_WITHOUT_MBM(dir);
  for (const auto& [family, count] : kObjectsPerFamily) {
    const std::vector<ManipulationProblem> yaml = LoadMbmFamily(dir + "/problems", family, 1, 3);
    const std::vector<ManipulationProblem> json =
        LoadCompactFamily(dir + "/compact_json/" + family + ".json", 1, 3);
    ASSERT_EQ(yaml.size(), 3u);
    ASSERT_EQ(json.size(), 3u);
    for (std::size_t k = 0; k < yaml.size(); ++k) ExpectSameProblem(yaml[k], json[k]);
    for (int index : {41, 75}) {
      ExpectSameProblem(
          LoadMbmFamily(dir + "/problems", family, index, index).front(),
          LoadCompactFamily(dir + "/compact_json/" + family + ".json", index, index).front());
    }
  }
}

TEST(MbmProblems, BoxFirstProblemValues) {
  SKIP_WITHOUT_MBM(dir);
  const std::string d = dir + "/problems/box_panda/";
  const ManipulationProblem p = LoadMbmProblem(d + "scene0001.yaml", d + "request0001.yaml");
  EXPECT_EQ(p.family, "box_panda");
  EXPECT_EQ(p.index, 1);
  JointVector start, goal;
  start << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  goal << 0.4534448383669427, 1.7628, 0.1941262264518609, -0.8667848896139277, -0.3798524112731043,
      2.606927984171601, -0.1898611792470702;
  EXPECT_EQ(p.start, start);
  EXPECT_EQ(p.goal, goal);
  const int can = p.world.FindObstacle("Can1");
  ASSERT_GE(can, 0);
  const Cylinder& c = p.world.obstacle(can).cylinder();
  EXPECT_EQ(c.radius, 0.03);
  EXPECT_EQ(c.half_height, 0.07);
  EXPECT_TRUE(testing::MatricesNear(
      c.X_WC.translation(),
      Eigen::Vector3d(0.5408380884576693, 0.3580155146897772, -0.3762264457751537), 0));
  const Box& base = p.world.obstacle(p.world.FindObstacle("base")).box();
  EXPECT_TRUE(testing::MatricesNear(base.half_size, Eigen::Vector3d(0.35, 0.35, 0.02), 1e-15));
  // The can hovers 2 cm above the box's base plate: a property of the MBM data (every box_panda
  // and table problem has this 0.02 m gap), checked here through the box signed distance.
  const Eigen::Vector3d can_bottom = c.X_WC * Eigen::Vector3d(0, 0, -c.half_height);
  EXPECT_NEAR(SignedDistance(base, can_bottom, nullptr), 0.02, 1e-9);
}

TEST(MbmProblems, GoalJointsMatchedByNameNotOrder) {
  SKIP_WITHOUT_MBM(dir);
  const std::string d = dir + "/problems/box_panda/";
  const ManipulationProblem original = LoadMbmProblem(d + "scene0001.yaml", d + "request0001.yaml");
  TempDir tmp;
  // Shuffled goal constraints and start names (fingers interleaved).
  WriteText(tmp.File("request.yaml"), R"(goal_constraints:
  - joint_constraints:
      - {joint_name: panda_joint5, position: -0.3798524112731043}
      - {position: 1.7628, joint_name: panda_joint2}
      - {joint_name: panda_joint7, position: -0.1898611792470702}
      - {joint_name: panda_finger_joint1, position: 0.04}
      - {joint_name: panda_joint1, position: 0.4534448383669427}
      - {joint_name: panda_joint6, position: 2.606927984171601}
      - {joint_name: panda_joint3, position: 0.1941262264518609}
      - {joint_name: panda_joint4, position: -0.8667848896139277}
start_state:
  joint_state:
    name: [panda_finger_joint1, panda_joint7, panda_joint6, panda_joint5, panda_joint4, panda_joint3, panda_joint2, panda_joint1, panda_finger_joint2]
    position: [0.065, 0.785, 1.571, 0, -2.356, 0, -0.785, 0, 0.065]
)");
  fs::copy_file(d + "scene0001.yaml", tmp.File("scene0001.yaml"));
  const ManipulationProblem shuffled =
      LoadMbmProblem(tmp.File("scene0001.yaml"), tmp.File("request.yaml"));
  EXPECT_EQ(shuffled.start, original.start);
  EXPECT_EQ(shuffled.goal, original.goal);
}

TEST(MbmProblems, FamilyAndRangeErrorsNameTheMissingFile) {
  SKIP_WITHOUT_MBM(dir);
  ExpectErrorContains([&] { LoadMbmFamily(dir + "/problems", "box_panda", 75, 76); },
                      {"missing scene file", "box_panda/scene0076.yaml"});
  ExpectErrorContains([&] { LoadMbmFamily(dir + "/problems", "shelf_panda", 1, 2); },
                      {"missing MBM family directory", "shelf_panda", "box_panda", "cage_panda"});
  ExpectErrorContains([&] { LoadMbmFamily(dir + "/problems", "box_panda", 0, 2); },
                      {"problem range 0..2"});
  ExpectErrorContains([&] { LoadCompactFamily(dir + "/compact_json/cage_panda.json", 74, 76); },
                      {"cage_panda.json", "no problem with index 76", "1..75"});
  ExpectErrorContains([&] { LoadCompactFamily(dir + "/compact_json/nope.json", 1, 1); },
                      {"missing", "compact_json/nope.json"});
}

// ---- small files in a temp dir --------------------------------------------------------------

const char* kRequest = R"(start_state:
  joint_state:
    name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, panda_joint5, panda_joint6, panda_joint7, panda_finger_joint1, panda_finger_joint2]
    position: [0, -0.785, 0, -2.356, 0, 1.571, 0.785, 0.065, 0.065]
goal_constraints:
  - joint_constraints:
      - {joint_name: panda_joint1, position: 0.1}
      - {joint_name: panda_joint2, position: 0.2}
      - {joint_name: panda_joint3, position: 0.3}
      - {joint_name: panda_joint4, position: -0.4}
      - {joint_name: panda_joint5, position: 0.5}
      - {joint_name: panda_joint6, position: 0.6}
      - {joint_name: panda_joint7, position: 0.7}
)";

/// A scene with one box and one cylinder; `edit` replaces text in it.
std::string Scene(const std::string& from = "", const std::string& to = "") {
  std::string s = R"(fixed_frame_transforms:
  - transform: {rotation: [0, 0, 0, 1], translation: [0, 0, 0]}
    child_frame_id: world
world:
  collision_objects:
    - id: plate
      primitives:
        - type: box
          dimensions: [0.4, 0.6, 0.02]
      primitive_poses:
        - position: [0.5, 0.1, -0.2]
          orientation: [0, 0, 0.7071068, 0.7071068]
    - id: Can1
      primitive_poses:
        - position: [0.5, 0.1, 0]
          orientation: [0, 0, 0, 1]
      primitives:
        - type: cylinder
          dimensions: [0.14, 0.03]
)";
  if (!from.empty()) {
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
  }
  return s;
}

struct Files {
  TempDir dir;
  std::string scene = dir.File("scene0007.yaml"), request = dir.File("request0007.yaml");
  Files(const std::string& scene_text, const std::string& request_text = kRequest) {
    WriteText(scene, scene_text);
    WriteText(request, request_text);
  }
  ManipulationProblem Load() const { return LoadMbmProblem(scene, request); }
};

TEST(MbmLoader, ReadsDimensionsAndPosesInMoveItConventions) {
  const Files f(Scene());
  const ManipulationProblem p = f.Load();
  EXPECT_EQ(p.index, 7);
  EXPECT_EQ(p.family, fs::path(f.dir.path()).filename().string());
  ASSERT_EQ(p.world.num_obstacles(), 2);
  const Box& plate = p.world.obstacle(0).box();
  EXPECT_TRUE(testing::MatricesNear(plate.half_size, Eigen::Vector3d(0.2, 0.3, 0.01), 1e-15));
  // 90 degrees about z: local x is world y. Quaternion normalised.
  EXPECT_TRUE(testing::MatricesNear(plate.X_WB.linear().col(0), Eigen::Vector3d(0, 1, 0), 1e-7));
  EXPECT_NEAR(
      (plate.X_WB.linear().transpose() * plate.X_WB.linear() - Eigen::Matrix3d::Identity()).norm(),
      0.0, 1e-15);
  const Cylinder& can = p.world.obstacle(1).cylinder();
  EXPECT_EQ(p.world.obstacle(1).id, "Can1");
  EXPECT_EQ(can.radius, 0.03);
  EXPECT_EQ(can.half_height, 0.07);
  JointVector goal;
  goal << 0.1, 0.2, 0.3, -0.4, 0.5, 0.6, 0.7;
  EXPECT_EQ(p.goal, goal);
  EXPECT_EQ(p.start(3), -2.356);
}

TEST(MbmLoader, UnknownPrimitiveTypeNamesFileObjectAndType) {
  const Files f(Scene("type: cylinder", "type: sphere"));
  ExpectErrorContains([&] { f.Load(); }, {f.scene, "'Can1'", "unknown primitive type 'sphere'"});
}

TEST(MbmLoader, WrongDimensionsAreRefused) {
  const Files two(Scene("[0.4, 0.6, 0.02]", "[0.4, 0.6]"));
  ExpectErrorContains([&] { two.Load(); },
                      {two.scene, "'plate'", "box dimensions need 3 values", "got 2"});
  const Files negative(Scene("[0.14, 0.03]", "[0.14, -0.03]"));
  ExpectErrorContains([&] { negative.Load(); },
                      {negative.scene, "'Can1'", "dimensions[1] = -0.03", "positive"});
  const Files nan(Scene("[0.14, 0.03]", "[.nan, 0.03]"));
  ExpectErrorContains([&] { nan.Load(); }, {nan.scene, "'Can1'", "not a finite number"});
  const Files text(Scene("[0.14, 0.03]", "[0.14, abc]"));
  ExpectErrorContains([&] { text.Load(); }, {text.scene, "'abc'", "not a finite number"});
}

TEST(MbmLoader, QuaternionsAreNormalisedButNotInvented) {
  const Files zero(Scene("orientation: [0, 0, 0, 1]", "orientation: [0, 0, 0, 0]"));
  ExpectErrorContains([&] { zero.Load(); }, {zero.scene, "'Can1'", "has norm 0"});
  const Files big(Scene("orientation: [0, 0, 0, 1]", "orientation: [0, 0, 0, 2]"));
  ExpectErrorContains([&] { big.Load(); }, {big.scene, "'Can1'", "has norm 2"});
  const Files three(Scene("orientation: [0, 0, 0, 1]", "orientation: [0, 0, 1]"));
  ExpectErrorContains([&] { three.Load(); }, {three.scene, "'Can1'", "expected 4 numbers, got 3"});
  const Files close(Scene("orientation: [0, 0, 0, 1]", "orientation: [0, 0, 0, 1.004]"));
  EXPECT_TRUE(close.Load().world.obstacle(1).cylinder().X_WC.linear().isApprox(
      Eigen::Matrix3d::Identity(), 1e-15));
}

TEST(MbmLoader, MissingOrRepeatedJointsNameFileAndJoint) {
  std::string no4 = kRequest;
  no4.replace(no4.find("      - {joint_name: panda_joint4, position: -0.4}\n"),
              std::string("      - {joint_name: panda_joint4, position: -0.4}\n").size(), "");
  const Files goal(Scene(), no4);
  ExpectErrorContains([&] { goal.Load(); }, {goal.request, "goal_constraints", "'panda_joint4'"});
  std::string no_start = kRequest;
  no_start.replace(no_start.find("panda_joint6, panda_joint7"), 26, "panda_joint6, panda_jointX");
  const Files start(Scene(), no_start);
  ExpectErrorContains([&] { start.Load(); }, {start.request, "start_state", "'panda_joint7'"});
  std::string twice = kRequest;
  twice.replace(twice.find("joint_name: panda_joint5"), 24, "joint_name: panda_joint2");
  const Files repeated(Scene(), twice);
  ExpectErrorContains([&] { repeated.Load(); }, {repeated.request, "'panda_joint2'", "2 times"});
  std::string short_positions = kRequest;
  short_positions.replace(short_positions.find(", 0.065, 0.065]"), 15, "]");
  const Files mismatch(Scene(), short_positions);
  ExpectErrorContains([&] { mismatch.Load(); }, {mismatch.request, "9 names but 7 positions"});
}

TEST(MbmLoader, MissingFilesAreNamed) {
  const Files f(Scene());
  ExpectErrorContains([&] { LoadMbmProblem(f.dir.File("nope.yaml"), f.request); },
                      {"missing scene file", f.dir.File("nope.yaml")});
  ExpectErrorContains([&] { LoadMbmProblem(f.scene, f.dir.File("nope.yaml")); },
                      {"missing request file", f.dir.File("nope.yaml")});
  ExpectErrorContains([&] { LoadMbmFamily(f.dir.File("nowhere"), "box_panda", 1, 1); },
                      {"missing MBM problems directory", f.dir.File("nowhere")});
}

TEST(MbmLoader, RefusesWhatItWouldOtherwiseMisread) {
  const Files swapped(kRequest, Scene());
  ExpectErrorContains([&] { swapped.Load(); }, {swapped.scene, "missing key 'world'"});
  const Files unknown(Scene("    - id: Can1\n", "    - id: Can1\n      color: red\n"));
  ExpectErrorContains([&] { unknown.Load(); }, {unknown.scene, "'Can1'", "unknown key 'color'"});
  const Files mesh(Scene("    - id: Can1\n", "    - id: Can1\n      meshes: [{vertices: []}]\n"));
  ExpectErrorContains([&] { mesh.Load(); }, {mesh.scene, "'Can1'", "meshes are not supported"});
  const Files frame(Scene("translation: [0, 0, 0]", "translation: [0, 0, 1]"));
  ExpectErrorContains([&] { frame.Load(); }, {frame.scene, "non-identity fixed_frame_transform"});
  const Files other_frame(
      Scene("    - id: Can1\n", "    - id: Can1\n      header: {frame_id: panda_hand}\n"));
  ExpectErrorContains([&] { other_frame.Load(); }, {"'Can1'", "frame_id 'panda_hand'"});
  const Files duplicate(Scene("id: plate", "id: Can1"));
  ExpectErrorContains([&] { duplicate.Load(); }, {duplicate.scene, "duplicate object id 'Can1'"});
  const Files broken(Scene("dimensions: [0.4, 0.6, 0.02]", "dimensions: [0.4, 0.6, 0.02"));
  ExpectErrorContains([&] { broken.Load(); }, {broken.scene, "not valid YAML"});
  const Files scalar_object(Scene("    - id: Can1\n", "    - just a string\n    - id: Can1\n"));
  ExpectErrorContains([&] { scalar_object.Load(); }, {scalar_object.scene});
  const Files mismatched(Scene("          dimensions: [0.4, 0.6, 0.02]\n",
                               "          dimensions: [0.4, 0.6, 0.02]\n"
                               "        - type: box\n          dimensions: [0.1, 0.1, 0.1]\n"));
  ExpectErrorContains([&] { mismatched.Load(); },
                      {mismatched.scene, "'plate'", "2 primitives but 1 primitive_poses"});
}

TEST(MbmLoader, SeveralPrimitivesAndAnObjectPose) {
  const Files f(Scene(R"(    - id: Can1
      primitive_poses:
        - position: [0.5, 0.1, 0]
          orientation: [0, 0, 0, 1]
      primitives:
        - type: cylinder
          dimensions: [0.14, 0.03])",
                      R"(    - id: pair
      pose: {position: [1, 0, 0], orientation: [0, 0, 0.7071068, 0.7071068]}
      primitive_poses:
        - {position: [0.1, 0, 0], orientation: [0, 0, 0, 1]}
        - {position: [0, 0, 0.5], orientation: [0, 0, 0, 1]}
      primitives:
        - {type: cylinder, dimensions: [0.14, 0.03]}
        - {type: box, dimensions: [0.1, 0.1, 0.1]})"));
  const ManipulationProblem p = f.Load();
  ASSERT_EQ(p.world.num_obstacles(), 3);
  EXPECT_EQ(p.world.obstacle(1).id, "pair[0]");
  EXPECT_EQ(p.world.obstacle(2).id, "pair[1]");
  // X_WO * X_OP: (1, 0, 0) + Rz(90) (0.1, 0, 0) = (1, 0.1, 0).
  EXPECT_TRUE(testing::MatricesNear(p.world.obstacle(1).cylinder().X_WC.translation(),
                                    Eigen::Vector3d(1, 0.1, 0), 1e-7));
  EXPECT_TRUE(testing::MatricesNear(p.world.obstacle(2).box().X_WB.translation(),
                                    Eigen::Vector3d(1, 0, 0.5), 1e-7));
}

// ---- compact JSON ---------------------------------------------------------------------------

std::string CompactJson(const std::string& obstacle_type = "box",
                        const std::string& joint_names = R"("panda_joint1", "panda_joint2",
    "panda_joint3", "panda_joint4", "panda_joint5", "panda_joint6", "panda_joint7")") {
  return R"({"set": "toy_panda", "frame": "panda_link0", "joint_names": [)" + joint_names + R"(],
  "problems": [
    {"index": 2, "start": [1, 2, 3, 4, 5, 6, 7], "goal": [7, 6, 5, 4, 3, 2, 1],
     "obstacles": [{"id": "b", "type": ")" +
         obstacle_type + R"(", "dims": [0.2, 0.4, 0.6],
                    "position": [1, 2, 3], "orientation_xyzw": [0, 0, 0, 1]}]},
    {"index": 1, "start": [0, 0, 0, 0, 0, 0, 0], "goal": [1, 1, 1, 1, 1, 1, 1], "obstacles": []}
  ]})";
}

TEST(CompactJson, ReadsProblemsByIndexAndJointName) {
  TempDir tmp;
  WriteText(tmp.File("toy.json"), CompactJson("box", R"("panda_joint7", "panda_joint6",
    "panda_joint5", "panda_joint4", "panda_joint3", "panda_joint2", "panda_joint1")"));
  const std::vector<ManipulationProblem> p = LoadCompactFamily(tmp.File("toy.json"), 1, 2);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].index, 1);
  EXPECT_EQ(p[0].world.num_obstacles(), 0);
  EXPECT_EQ(p[1].family, "toy_panda");
  JointVector reversed;
  reversed << 7, 6, 5, 4, 3, 2, 1;
  EXPECT_EQ(p[1].start, reversed);  // listed for joint7..joint1
  EXPECT_TRUE(testing::MatricesNear(p[1].world.obstacle(0).box().half_size,
                                    Eigen::Vector3d(0.1, 0.2, 0.3), 1e-15));
}

TEST(CompactJson, BadInputIsNamed) {
  TempDir tmp;
  WriteText(tmp.File("cone.json"), CompactJson("cone"));
  ExpectErrorContains([&] { LoadCompactFamily(tmp.File("cone.json"), 2, 2); },
                      {tmp.File("cone.json"), "'b'", "unknown primitive type 'cone'"});
  WriteText(tmp.File("joints.json"), CompactJson("box", R"("panda_joint1", "panda_joint2",
    "panda_joint3", "panda_joint4", "panda_joint5", "panda_joint6", "panda_joint8")"));
  ExpectErrorContains([&] { LoadCompactFamily(tmp.File("joints.json"), 1, 1); },
                      {tmp.File("joints.json"), "'panda_joint7'"});
  ExpectErrorContains([&] { LoadCompactFamily(tmp.File("cone.json"), 3, 3); },
                      {"no problem with index 3", "indices 1..2"});
  std::string extra = CompactJson();
  extra.replace(extra.find("\"dims\""), 6, "\"size\"");
  WriteText(tmp.File("extra.json"), extra);
  ExpectErrorContains([&] { LoadCompactFamily(tmp.File("extra.json"), 2, 2); },
                      {tmp.File("extra.json"), "unknown key 'size'"});
}

// Found by fuzz_mbm_problem (tests/fuzz/corpus/mbm_problem/regress_multiline_yaml_error, which
// the ctest fuzz.mbm_problem replays): a backslash before a line break in a quoted string made
// yaml-cpp's message (and so the Error) span two lines; names and values quoted from the files
// (below) could do the same.
TEST(CompactJson, ErrorsStayOnOneLine) {
  TempDir tmp;
  WriteText(tmp.File("cone.json"), CompactJson("co\\nne"));
  try {
    LoadCompactFamily(tmp.File("cone.json"), 2, 2);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find("unknown primitive type 'co\\nne'"), std::string::npos) << what;
  }
  const Files f(Scene("id: Can1", "id: \"Can\\n1\"\n      bad: 1"));
  try {
    f.Load();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find(f.scene), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace foresight::manipulation
