#include "inference/manipulation/mbm_problem.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/one_line.h"
#include "core/parse.h"

namespace foresight::manipulation {
namespace {

namespace fs = std::filesystem;

/// A quaternion whose norm is further than this from 1 is refused rather than normalised.
constexpr double kQuaternionNormTolerance = 0.01;

/// "file:line" of a parsed node (just "file" when the node has no position).
std::string Where(const std::string& file, const YAML::Node& node) {
  if (!node.IsDefined() || node.Mark().is_null()) return file;
  return file + ":" + std::to_string(node.Mark().line + 1);
}

YAML::Node LoadYaml(const std::string& path, const char* what) {
  std::error_code ec;
  FS_THROW_UNLESS(fs::is_regular_file(path, ec), "missing ", what, " file ", path);
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), "cannot open ", what, " file ", path);
  std::stringstream text;
  text << in.rdbuf();
  YAML::Node node;
  try {
    node = YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    Fail(path, e.mark.is_null() ? "" : ":" + std::to_string(e.mark.line + 1),
         ": not valid YAML/JSON: ", e.msg);
  }
  FS_THROW_UNLESS(node.IsMap(), path, ": expected a mapping at the top level of the ", what,
                  " file");
  return node;
}

/// parent[key], which must be present and not null.
YAML::Node Required(const YAML::Node& parent, const char* key, const std::string& file,
                    const std::string& context) {
  const YAML::Node child = parent[key];
  FS_THROW_UNLESS(child.IsDefined() && !child.IsNull(), Where(file, parent), ": ", context,
                  ": missing key '", key, "'");
  return child;
}

/// Every key of `map` is in `known`.
void CheckKeys(const YAML::Node& map, const std::set<std::string>& known, const std::string& file,
               const std::string& context) {
  FS_THROW_UNLESS(map.IsMap(), Where(file, map), ": ", context, ": expected a mapping");
  for (const auto& kv : map) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "<not a string>";
    if (known.count(key)) continue;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    Fail(Where(file, kv.first), ": ", context, ": unknown key '", key, "' (known: ", list, ")");
  }
}

std::string Text(const YAML::Node& node, const std::string& file, const std::string& context) {
  FS_THROW_UNLESS(node.IsScalar(), Where(file, node), ": ", context, ": expected a string");
  return node.Scalar();
}

double Number(const YAML::Node& node, const std::string& file, const std::string& context) {
  FS_THROW_UNLESS(node.IsScalar(), Where(file, node), ": ", context, ": expected a number");
  const std::optional<double> v = ParseDouble(node.Scalar());
  FS_THROW_UNLESS(v && std::isfinite(*v), Where(file, node), ": ", context, ": value '",
                  node.Scalar(), "' is not a finite number");
  return *v;
}

/// A list of numbers; `count` >= 0 demands that many.
std::vector<double> Numbers(const YAML::Node& node, const std::string& file,
                            const std::string& context, int count = -1) {
  FS_THROW_UNLESS(node.IsSequence(), Where(file, node), ": ", context,
                  ": expected a list of numbers");
  FS_THROW_UNLESS(count < 0 || static_cast<int>(node.size()) == count, Where(file, node), ": ",
                  context, ": expected ", count, " numbers, got ", node.size());
  std::vector<double> out;
  for (std::size_t i = 0; i < node.size(); ++i)
    out.push_back(Number(node[i], file, context + "[" + std::to_string(i) + "]"));
  return out;
}

std::vector<std::string> Strings(const YAML::Node& node, const std::string& file,
                                 const std::string& context) {
  FS_THROW_UNLESS(node.IsSequence(), Where(file, node), ": ", context,
                  ": expected a list of strings");
  std::vector<std::string> out;
  for (std::size_t i = 0; i < node.size(); ++i)
    out.push_back(Text(node[i], file, context + "[" + std::to_string(i) + "]"));
  return out;
}

/// A pose from position [x, y, z] and a quaternion [x, y, z, w] (normalised).
Eigen::Isometry3d Pose(const std::vector<double>& position, const std::vector<double>& xyzw,
                       const std::string& where, const std::string& context) {
  const Eigen::Quaterniond q(xyzw[3], xyzw[0], xyzw[1], xyzw[2]);
  const double norm = q.norm();
  FS_THROW_UNLESS(std::abs(norm - 1.0) <= kQuaternionNormTolerance, where, ": ", context,
                  ": orientation [", xyzw[0], ", ", xyzw[1], ", ", xyzw[2], ", ", xyzw[3],
                  "] (x, y, z, w) has norm ", norm, "; a rotation needs a unit quaternion (within ",
                  kQuaternionNormTolerance, ")");
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q.normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(position[0], position[1], position[2]);
  return X;
}

/// Adds one MoveIt primitive (shared by both readers, so they build identical worlds).
void AddPrimitive(const std::string& name, const std::string& type, const std::vector<double>& dims,
                  const Eigen::Isometry3d& X_WP, const std::string& where, World* world) {
  auto check_dims = [&](std::size_t count, const char* layout) {
    FS_THROW_UNLESS(dims.size() == count, where, ": object '", name, "': ", type,
                    " dimensions need ", count, " values ", layout, ", got ", dims.size());
    for (std::size_t i = 0; i < dims.size(); ++i)
      FS_THROW_UNLESS(dims[i] > 0.0, where, ": object '", name, "': ", type, " dimensions[", i,
                      "] = ", dims[i], " must be positive (m)");
  };
  if (type != "box" && type != "cylinder")
    Fail(where, ": object '", name, "': unknown primitive type '", type,
         "' (expected box or cylinder)");
  try {
    if (type == "box") {
      check_dims(3, "[x, y, z] (full side lengths)");
      world->AddBox(name, Box{X_WP, 0.5 * Eigen::Vector3d(dims[0], dims[1], dims[2])});
    } else {
      check_dims(2, "[height, radius]");
      world->AddCylinder(name, Cylinder{X_WP, dims[1], 0.5 * dims[0]});
    }
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind(where, 0) == 0) throw;
    Fail(where, ": ", what);
  }
}

/// values[name] for each arm joint, in JointVector order.
JointVector ArmJoints(const std::vector<std::string>& names, const std::vector<double>& values,
                      const std::string& where, const std::string& context) {
  JointVector q;
  const std::vector<std::string>& arm = MbmArmJointNames();
  for (int j = 0; j < kDof; ++j) {
    const auto n = std::count(names.begin(), names.end(), arm[static_cast<std::size_t>(j)]);
    FS_THROW_UNLESS(n > 0, where, ": ", context, " has no joint '",
                    arm[static_cast<std::size_t>(j)], "'");
    FS_THROW_UNLESS(n == 1, where, ": ", context, " lists joint '",
                    arm[static_cast<std::size_t>(j)], "' ", n, " times");
    const auto it = std::find(names.begin(), names.end(), arm[static_cast<std::size_t>(j)]);
    q(j) = values[static_cast<std::size_t>(it - names.begin())];
  }
  return q;
}

bool IsIdentityTransform(const YAML::Node& transform, const std::string& file) {
  const std::vector<double> t = Numbers(Required(transform, "translation", file, "transform"), file,
                                        "transform translation", 3);
  const std::vector<double> r =
      Numbers(Required(transform, "rotation", file, "transform"), file, "transform rotation", 4);
  const double tol = 1e-12;
  return std::abs(t[0]) < tol && std::abs(t[1]) < tol && std::abs(t[2]) < tol &&
         std::abs(r[0]) < tol && std::abs(r[1]) < tol && std::abs(r[2]) < tol &&
         std::abs(std::abs(r[3]) - 1.0) < tol;
}

/// world.collision_objects of a MoveIt PlanningScene.
World ReadSceneNodes(const std::string& file) {
  const YAML::Node scene = LoadYaml(file, "scene");
  if (const YAML::Node fixed = scene["fixed_frame_transforms"]; fixed && !fixed.IsNull()) {
    FS_THROW_UNLESS(fixed.IsSequence(), Where(file, fixed),
                    ": fixed_frame_transforms: expected a list");
    for (const YAML::Node& f : fixed) {
      FS_THROW_UNLESS(IsIdentityTransform(Required(f, "transform", file, "fixed frame"), file),
                      Where(file, f),
                      ": a non-identity fixed_frame_transform is not supported (objects must be "
                      "given in the robot base frame)");
    }
  }
  const YAML::Node world_node =
      Required(scene, "world", file, "scene (is this a MoveIt PlanningScene?)");
  World world;
  const YAML::Node objects = world_node["collision_objects"];
  if (!objects || objects.IsNull()) return world;
  FS_THROW_UNLESS(objects.IsSequence(), Where(file, objects),
                  ": world.collision_objects: expected a list");
  std::set<std::string> ids;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const YAML::Node o = objects[i];
    const std::string context = "collision object " + std::to_string(i);
    const std::string id = Text(Required(o, "id", file, context), file, context + " id");
    const std::string what = "object '" + id + "'";
    CheckKeys(o,
              {"id", "header", "pose", "primitives", "primitive_poses", "meshes", "mesh_poses",
               "planes", "plane_poses", "subframe_names", "subframe_poses", "operation", "type"},
              file, what);
    FS_THROW_UNLESS(ids.insert(id).second, Where(file, o), ": duplicate object id '", id, "'");
    for (const char* unsupported : {"meshes", "planes"}) {
      const YAML::Node n = o[unsupported];
      FS_THROW_UNLESS(!n || n.IsNull() || (n.IsSequence() && n.size() == 0), Where(file, n), ": ",
                      what, ": ", unsupported,
                      " are not supported (only box and cylinder primitives)");
    }
    if (const YAML::Node op = o["operation"]; op && !op.IsNull()) {
      const std::string s = Text(op, file, what + " operation");
      FS_THROW_UNLESS(s == "0" || s == "ADD" || s == "add", Where(file, op), ": ", what,
                      ": operation '", s, "' is not supported (only ADD)");
    }
    if (const YAML::Node header = o["header"]; header && !header.IsNull()) {
      const YAML::Node frame = header["frame_id"];
      const std::string f = frame && !frame.IsNull() ? Text(frame, file, what + " frame_id") : "";
      FS_THROW_UNLESS(f.empty() || f == "world" || f == "panda_link0" || f == "/world",
                      Where(file, header), ": ", what, ": frame_id '", f,
                      "' is not supported (objects must be in world = panda_link0)");
    }
    Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
    if (const YAML::Node pose = o["pose"]; pose && !pose.IsNull()) {
      CheckKeys(pose, {"position", "orientation"}, file, what + " pose");
      X_WO = Pose(Numbers(Required(pose, "position", file, what + " pose"), file,
                          what + " pose position", 3),
                  Numbers(Required(pose, "orientation", file, what + " pose"), file,
                          what + " pose orientation", 4),
                  Where(file, pose), what + " pose");
    }
    const YAML::Node primitives = Required(o, "primitives", file, what);
    const YAML::Node poses = Required(o, "primitive_poses", file, what);
    FS_THROW_UNLESS(primitives.IsSequence() && poses.IsSequence(), Where(file, o), ": ", what,
                    ": primitives and primitive_poses must be lists");
    FS_THROW_UNLESS(primitives.size() > 0, Where(file, primitives), ": ", what,
                    ": has no primitives");
    FS_THROW_UNLESS(primitives.size() == poses.size(), Where(file, primitives), ": ", what, ": ",
                    primitives.size(), " primitives but ", poses.size(), " primitive_poses");
    for (std::size_t k = 0; k < primitives.size(); ++k) {
      const std::string name = primitives.size() == 1 ? id : id + "[" + std::to_string(k) + "]";
      const std::string pwhat = "object '" + name + "'";
      const YAML::Node prim = primitives[k];
      const YAML::Node pose = poses[k];
      CheckKeys(prim, {"type", "dimensions"}, file, pwhat + " primitive");
      CheckKeys(pose, {"position", "orientation"}, file, pwhat + " primitive pose");
      const std::string type = Text(Required(prim, "type", file, pwhat), file, pwhat + " type");
      const std::vector<double> dims =
          Numbers(Required(prim, "dimensions", file, pwhat), file, pwhat + " dimensions");
      const Eigen::Isometry3d X_OP = Pose(
          Numbers(Required(pose, "position", file, pwhat + " pose"), file, pwhat + " position", 3),
          Numbers(Required(pose, "orientation", file, pwhat + " pose"), file,
                  pwhat + " orientation", 4),
          Where(file, pose), pwhat);
      AddPrimitive(name, type, dims, X_WO * X_OP, Where(file, prim), &world);
    }
  }
  return world;
}

/// Start and joint-space goal of a MoveIt MotionPlanRequest.
void ReadRequestNodes(const std::string& file, JointVector* start, JointVector* goal) {
  const YAML::Node request = LoadYaml(file, "request");
  const YAML::Node state =
      Required(Required(request, "start_state", file, "request (is this a MotionPlanRequest?)"),
               "joint_state", file, "start_state");
  const std::vector<std::string> names =
      Strings(Required(state, "name", file, "start_state.joint_state"), file,
              "start_state.joint_state.name");
  const std::vector<double> positions =
      Numbers(Required(state, "position", file, "start_state.joint_state"), file,
              "start_state.joint_state.position");
  FS_THROW_UNLESS(names.size() == positions.size(), Where(file, state),
                  ": start_state.joint_state has ", names.size(), " names but ", positions.size(),
                  " positions");
  *start = ArmJoints(names, positions, Where(file, state), "start_state");

  const YAML::Node goals = Required(request, "goal_constraints", file, "request");
  FS_THROW_UNLESS(goals.IsSequence() && goals.size() == 1, Where(file, goals),
                  ": goal_constraints: expected exactly one entry (a joint-space goal), got ",
                  goals.IsSequence() ? goals.size() : 0);
  const YAML::Node constraints =
      Required(goals[0], "joint_constraints", file, "goal_constraints[0]");
  FS_THROW_UNLESS(constraints.IsSequence(), Where(file, constraints),
                  ": goal_constraints[0].joint_constraints: expected a list");
  std::vector<std::string> goal_names;
  std::vector<double> goal_values;
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    const std::string context = "joint_constraints[" + std::to_string(i) + "]";
    goal_names.push_back(
        Text(Required(constraints[i], "joint_name", file, context), file, context + ".joint_name"));
    goal_values.push_back(
        Number(Required(constraints[i], "position", file, context), file, context + ".position"));
  }
  *goal = ArmJoints(goal_names, goal_values, Where(file, constraints),
                    "goal_constraints[0].joint_constraints");
}

/// yaml-cpp throws its own exceptions for shapes the readers do not expect (a subscript on a
/// scalar, say): they become foresight::Error naming the file.
World ReadScene(const std::string& file) {
  try {
    return ReadSceneNodes(file);
  } catch (const YAML::Exception& e) {
    Fail(file, e.mark.is_null() ? "" : ":" + std::to_string(e.mark.line + 1),
         ": unexpected scene structure: ", e.msg);
  }
}

void ReadRequest(const std::string& file, JointVector* start, JointVector* goal) {
  try {
    ReadRequestNodes(file, start, goal);
  } catch (const YAML::Exception& e) {
    Fail(file, e.mark.is_null() ? "" : ":" + std::to_string(e.mark.line + 1),
         ": unexpected request structure: ", e.msg);
  }
}

std::string ProblemFile(const std::string& dir, const char* kind, int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%s%04d.yaml", kind, index);
  return (fs::path(dir) / name).string();
}

void CheckRange(int first, int last, const std::string& where) {
  FS_THROW_UNLESS(first >= 1 && last >= first, where, ": problem range ", first, "..", last,
                  " is not valid (1-based, first <= last)");
}

}  // namespace

const std::vector<std::string>& MbmArmJointNames() {
  static const std::vector<std::string> names = {"panda_joint1", "panda_joint2", "panda_joint3",
                                                 "panda_joint4", "panda_joint5", "panda_joint6",
                                                 "panda_joint7"};
  return names;
}

ManipulationProblem LoadMbmProblem(const std::string& scene_yaml, const std::string& request_yaml) {
  ManipulationProblem p;
  try {
    p.world = ReadScene(scene_yaml);
    ReadRequest(request_yaml, &p.start, &p.goal);
  } catch (const Error& e) {
    throw Error(OneLine(e.what()));  // names, keys and values from the files may hold newlines
  }
  const fs::path scene(scene_yaml);
  p.family = scene.parent_path().filename().string();
  std::smatch m;
  const std::string stem = scene.filename().string();
  if (std::regex_match(stem, m, std::regex(R"(scene0*(\d+)\.yaml)"))) {
    const std::optional<long long> index = ParseInteger(m[1]);
    FS_THROW_UNLESS(index && *index <= std::numeric_limits<int>::max(), scene_yaml,
                    ": problem number '", m[1].str(), "' in the file name is out of range");
    p.index = static_cast<int>(*index);
  }
  p.source = scene_yaml + ", " + request_yaml;
  return p;
}

std::vector<ManipulationProblem> LoadMbmFamily(const std::string& problems_dir,
                                               const std::string& family, int first, int last) {
  std::error_code ec;
  FS_THROW_UNLESS(fs::is_directory(problems_dir, ec), "missing MBM problems directory ",
                  problems_dir);
  const fs::path dir = fs::path(problems_dir) / family;
  if (!fs::is_directory(dir, ec)) {
    std::vector<std::string> present;
    for (const auto& e : fs::directory_iterator(problems_dir))
      if (e.is_directory()) present.push_back(e.path().filename().string());
    std::sort(present.begin(), present.end());
    std::string list;
    for (const auto& f : present) list += (list.empty() ? "" : ", ") + f;
    Fail("missing MBM family directory ", dir.string(), " (families present: ", list, ")");
  }
  CheckRange(first, last, dir.string());
  std::vector<ManipulationProblem> out;
  for (int i = first; i <= last; ++i) {
    ManipulationProblem p = LoadMbmProblem(ProblemFile(dir.string(), "scene", i),
                                           ProblemFile(dir.string(), "request", i));
    p.family = family;
    p.index = i;
    out.push_back(std::move(p));
  }
  return out;
}

namespace {
std::vector<ManipulationProblem> ReadCompactFamily(const std::string& json_path, int first,
                                                   int last) {
  const std::string& file = json_path;
  const YAML::Node root = LoadYaml(file, "compact MBM JSON");
  CheckKeys(root, {"set", "frame", "joint_names", "ee_fk_note", "problems"}, file, "top level");
  CheckRange(first, last, file);
  const std::string family = Text(Required(root, "set", file, "top level"), file, "set");
  const std::vector<std::string> joint_names =
      Strings(Required(root, "joint_names", file, "top level"), file, "joint_names");
  const YAML::Node problems = Required(root, "problems", file, "top level");
  FS_THROW_UNLESS(problems.IsSequence(), Where(file, problems), ": problems: expected a list");

  std::map<int, YAML::Node> by_index;
  for (std::size_t i = 0; i < problems.size(); ++i) {
    const YAML::Node p = problems[i];
    const std::string context = "problems[" + std::to_string(i) + "]";
    const double index = Number(Required(p, "index", file, context), file, context + ".index");
    FS_THROW_UNLESS(index == std::floor(index) && index >= 1 && index <= 1e6, Where(file, p), ": ",
                    context, ": index ", index, " is not a positive integer");
    FS_THROW_UNLESS(by_index.emplace(static_cast<int>(index), p).second, Where(file, p), ": ",
                    context, ": duplicate problem index ", index);
  }
  std::vector<ManipulationProblem> out;
  for (int i = first; i <= last; ++i) {
    const auto it = by_index.find(i);
    FS_THROW_UNLESS(it != by_index.end(), file, ": no problem with index ", i, " (the file holds ",
                    by_index.size(), " problems",
                    by_index.empty() ? std::string()
                                     : ", indices " + std::to_string(by_index.begin()->first) +
                                           ".." + std::to_string(by_index.rbegin()->first),
                    ")");
    const YAML::Node p = it->second;
    const std::string context = "problem " + std::to_string(i);
    CheckKeys(p,
              {"index", "scene_file", "request_file", "start", "start_fingers", "goal",
               "start_grasptarget_position", "goal_grasptarget_position",
               "goal_grasptarget_quat_xyzw", "goal_link8_position", "obstacles"},
              file, context);
    ManipulationProblem problem;
    problem.family = family;
    problem.index = i;
    problem.source = file + " [problem " + std::to_string(i) + "]";
    const int n = static_cast<int>(joint_names.size());
    problem.start = ArmJoints(
        joint_names, Numbers(Required(p, "start", file, context), file, context + " start", n),
        Where(file, p), context + " joint_names/start");
    problem.goal = ArmJoints(
        joint_names, Numbers(Required(p, "goal", file, context), file, context + " goal", n),
        Where(file, p), context + " joint_names/goal");
    const YAML::Node obstacles = Required(p, "obstacles", file, context);
    FS_THROW_UNLESS(obstacles.IsSequence(), Where(file, obstacles), ": ", context,
                    ": obstacles: expected a list");
    for (std::size_t k = 0; k < obstacles.size(); ++k) {
      const YAML::Node o = obstacles[k];
      const std::string ocontext = context + " obstacle " + std::to_string(k);
      CheckKeys(o, {"id", "type", "dims", "position", "orientation_xyzw"}, file, ocontext);
      const std::string id = Text(Required(o, "id", file, ocontext), file, ocontext + " id");
      const std::string what = context + " object '" + id + "'";
      const std::string type = Text(Required(o, "type", file, what), file, what + " type");
      const std::vector<double> dims =
          Numbers(Required(o, "dims", file, what), file, what + " dims");
      const Eigen::Isometry3d X_WP = Pose(
          Numbers(Required(o, "position", file, what), file, what + " position", 3),
          Numbers(Required(o, "orientation_xyzw", file, what), file, what + " orientation_xyzw", 4),
          Where(file, o), what);
      FS_THROW_UNLESS(problem.world.FindObstacle(id) < 0, Where(file, o), ": ", context,
                      ": duplicate object id '", id, "'");
      AddPrimitive(id, type, dims, X_WP, Where(file, o), &problem.world);
    }
    out.push_back(std::move(problem));
  }
  return out;
}

}  // namespace

std::vector<ManipulationProblem> LoadCompactFamily(const std::string& json_path, int first,
                                                   int last) {
  try {
    return ReadCompactFamily(json_path, first, last);
  } catch (const YAML::Exception& e) {
    Fail(json_path, ": unexpected structure: ", OneLine(e.msg));
  } catch (const Error& e) {
    throw Error(OneLine(e.what()));  // names, keys and values from the file may hold newlines
  }
}

}  // namespace foresight::manipulation
