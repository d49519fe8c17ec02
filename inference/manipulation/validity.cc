#include "inference/manipulation/validity.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace foresight::manipulation {
namespace {
/// Most states one CheckMotion may check (a resolution far below the segment length is an error,
/// not a silent end-points-only check or an hour of checks).
constexpr double kMaxMotionStates = 1e7;
}  // namespace

const char* ToString(Validity validity) {
  switch (validity) {
    case Validity::kValid:
      return "valid";
    case Validity::kJointLimits:
      return "joint_limits";
    case Validity::kWorldCollision:
      return "world_collision";
    case Validity::kSelfCollision:
      return "self_collision";
    case Validity::kNonFinite:
      return "non_finite";
  }
  return "unknown";
}

ValidityChecker::ValidityChecker(const RobotModel& robot, const World& world, double margin)
    : robot_(robot), world_(world), margin_(margin) {
  FS_THROW_UNLESS(std::isfinite(margin) && margin >= 0,
                  "validity checker: margin must be finite and >= 0, got ", margin);
}

Validity ValidityChecker::Check(const JointVector& q, KinematicsData* data) const {
  if (!q.allFinite()) return Validity::kNonFinite;
  const JointLimits& limits = robot_.limits();
  if ((q.array() < limits.lower.array()).any() || (q.array() > limits.upper.array()).any())
    return Validity::kJointLimits;
  ForwardKinematics(robot_, q, data);
  const auto& spheres = robot_.spheres();
  for (int s = 0; s < static_cast<int>(spheres.size()); ++s) {
    if (world_.SignedDistance(data->p_WS.col(s), nullptr) - spheres[s].radius < margin_)
      return Validity::kWorldCollision;
  }
  for (const auto& [a, b] : robot_.self_collision_pairs()) {
    const double reach = spheres[a].radius + spheres[b].radius;
    if ((data->p_WS.col(a) - data->p_WS.col(b)).squaredNorm() < reach * reach)
      return Validity::kSelfCollision;
  }
  return Validity::kValid;
}

Validity ValidityChecker::CheckMotion(const JointVector& a, const JointVector& b, double resolution,
                                      KinematicsData* data, double* first_invalid) const {
  FS_THROW_UNLESS(resolution > 0, "validity checker: resolution must be positive, got ",
                  resolution);
  if (!a.allFinite() || !b.allFinite()) {  // no segment to walk: report the first bad end
    const Validity v = Check(a, data);
    if (first_invalid) *first_invalid = v != Validity::kValid ? 0.0 : 1.0;
    return v != Validity::kValid ? v : Validity::kNonFinite;
  }
  const double length = (b - a).norm();
  const double count = std::ceil(length / resolution);
  FS_THROW_UNLESS(std::isfinite(count) && count <= kMaxMotionStates,
                  "validity checker: segment of ", length, " rad at resolution ", resolution,
                  " needs ", count, " states (more than ", kMaxMotionStates, ")");
  const int segments = std::max(1, static_cast<int>(count));
  for (int i = 0; i <= segments; ++i) {
    const double s = static_cast<double>(i) / segments;
    // The last state is b itself (a + 1.0 (b - a) can differ from b in the last bit).
    const Validity v = Check(i == segments ? b : JointVector(a + s * (b - a)), data);
    if (v != Validity::kValid) {
      if (first_invalid) *first_invalid = s;
      return v;
    }
  }
  return Validity::kValid;
}

double ValidityChecker::MinWorldClearance(const JointVector& q, KinematicsData* data) const {
  if (!q.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  ForwardKinematics(robot_, q, data);
  double clearance = std::numeric_limits<double>::infinity();
  const auto& spheres = robot_.spheres();
  for (int s = 0; s < static_cast<int>(spheres.size()); ++s)
    clearance =
        std::min(clearance, world_.SignedDistance(data->p_WS.col(s), nullptr) - spheres[s].radius);
  return clearance;
}

}  // namespace foresight::manipulation
