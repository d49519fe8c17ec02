#pragma once
/// MotionBenchMaker problems (Chamzas et al., RA-L 2022) for the Panda: a world of boxes and
/// cylinders plus a start and a joint-space goal (thesis ch 9, GFCS experiments). Two readers of
/// the same problems, which agree exactly (tested):
///
/// - the MoveIt files, `problems/<family>/sceneNNNN.yaml` (moveit_msgs/PlanningScene) and
///   `requestNNNN.yaml` (moveit_msgs/MotionPlanRequest);
/// - the derived `compact_json/<family>.json` (one file per family; parsed by yaml-cpp).
///
/// Data layout and provenance: ../shared/data/motionbenchmaker_panda/README.md. Frame W is the
/// robot base panda_link0. Joint values are matched by name (panda_joint1..7), never by position;
/// finger joints and every other name are ignored.
///
/// What is read from a scene: `world.collision_objects[]` with `id`, `primitives[]` (`type` box |
/// cylinder, `dimensions` box [x, y, z] full side lengths, cylinder [height, radius]) and
/// `primitive_poses[]` (`position`, `orientation` quaternion [x, y, z, w], normalised). An object
/// may hold several primitives; each becomes one obstacle, named `id` when the object has one
/// primitive and `id[k]` otherwise (MBM objects all have one). An optional object `pose` is
/// composed in front of the primitive poses (newer MoveIt). `fixed_frame_transforms` must be
/// identities and object header frames empty, "world" or "panda_link0"; meshes and planes are
/// refused. The dummy `robot_state` and the `allowed_collision_matrix` are ignored.
/// From a request: `start_state.joint_state` (`name`, `position`) and the one
/// `goal_constraints[0].joint_constraints[]` (`joint_name`, `position`).
///
/// Bad input throws foresight::Error naming the file (file:line where the YAML node has one), the
/// object id and the offending value: a missing file, unknown primitive type, wrong dimension
/// count, non-positive or non-finite numbers, a zero/non-finite quaternion or one whose norm is not
/// within 1% of 1, a missing or repeated arm joint, duplicate object ids, unknown keys in a
/// collision object or a compact-JSON entry.

#include <string>
#include <vector>

#include "inference/manipulation/joint_types.h"
#include "inference/manipulation/world.h"

namespace foresight::manipulation {

/// One motion problem: reach `goal` from `start` in `world`.
struct ManipulationProblem {
  std::string family;  ///< e.g. "box_panda" (the MBM family directory), or "synthetic"
  int index = 0;       ///< 1-based problem number within the family (0 when unknown)
  JointVector start = JointVector::Zero();  ///< [7] panda_joint1..7 (rad)
  JointVector goal = JointVector::Zero();   ///< [7] panda_joint1..7 (rad)
  World world;
  std::string source;  ///< the file(s) it came from, for messages
};

/// The Panda arm joint names in JointVector order: panda_joint1 .. panda_joint7.
const std::vector<std::string>& MbmArmJointNames();

/// Reads one problem from a MoveIt scene and request. family = the scene's parent directory name,
/// index = the number in "sceneNNNN.yaml" (0 when the name has none).
ManipulationProblem LoadMbmProblem(const std::string& scene_yaml, const std::string& request_yaml);

/// Problems first..last (1-based, inclusive) of `family` (e.g. "box_panda") from
/// `problems_dir`/<family>/{scene,request}NNNN.yaml. Errors name the missing directory (listing the
/// families present) or the first missing file.
std::vector<ManipulationProblem> LoadMbmFamily(const std::string& problems_dir,
                                               const std::string& family, int first, int last);

/// Problems with index first..last (inclusive) from a compact JSON file
/// (`compact_json/<family>.json`); family = its "set". Errors name the file and a missing index.
std::vector<ManipulationProblem> LoadCompactFamily(const std::string& json_path, int first,
                                                   int last);

}  // namespace foresight::manipulation
