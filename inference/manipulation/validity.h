#pragma once
/// The one validity checker every manipulation method uses (GFCS, the geometric fabric, the OMPL
/// planners, the metrics and the problem generators): joint limits, body spheres against the
/// world's boxes and cylinders, and the robot's checked sphere pairs (self-collision).

#include <Eigen/Core>

#include "inference/manipulation/joint_types.h"
#include "inference/manipulation/robot_model.h"
#include "inference/manipulation/world.h"

namespace foresight::manipulation {

enum class Validity {
  kValid,
  kJointLimits,     ///< a joint outside [lower, upper]
  kWorldCollision,  ///< a sphere closer than `margin` to an obstacle (or inside it)
  kSelfCollision,   ///< two checked spheres overlap
  kNonFinite,       ///< a non-finite joint angle
};
const char* ToString(Validity validity);

class ValidityChecker {
 public:
  /// `robot` and `world` must outlive the checker. `margin` (m) is the clearance a sphere must
  /// keep from obstacles (0: touching is valid, penetration is not).
  ValidityChecker(const RobotModel& robot, const World& world, double margin = 0.0);

  const RobotModel& robot() const { return robot_; }
  const World& world() const { return world_; }

  /// Checks one configuration, using `data` as work buffers (no allocation).
  /// @param q [7] joint angles (rad)
  Validity Check(const JointVector& q, KinematicsData* data) const;

  /// Checks the straight C-space segment a -> b at states no more than `resolution` (rad, 2-norm)
  /// apart, both ends included. Returns the first invalid state's validity (kValid if none) and,
  /// when `first_invalid` is given, the fraction along the segment where it occurred. More than
  /// 1e7 states (resolution far below the length) is an Error.
  Validity CheckMotion(const JointVector& a, const JointVector& b, double resolution,
                       KinematicsData* data, double* first_invalid = nullptr) const;

  /// Minimum sphere clearance to the world (m) at q (+inf in an empty world, NaN for a
  /// non-finite q).
  double MinWorldClearance(const JointVector& q, KinematicsData* data) const;

 private:
  const RobotModel& robot_;
  const World& world_;
  double margin_;
};

}  // namespace foresight::manipulation
