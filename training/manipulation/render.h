#pragma once
/// End-effector paths of a few problems, as the thesis's figure "Examples of end-effector
/// trajectories": per problem a top view (x-y) and a side view (x-z) with the obstacles'
/// outlines, one colour per method, start and goal marked, axes in metres.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "inference/manipulation/world.h"

namespace foresight::manipulation {

struct PlanProblemPicture {
  int problem = 0;
  const manipulation::World* world = nullptr;  ///< must outlive the rendering
  /// (method, end-effector positions [3 x T]); an empty path is a failure (drawn in the legend).
  std::vector<std::pair<std::string, Eigen::Matrix3Xd>> paths;
};

/// Writes a PNG with one row per picture. Throws Error when the file cannot be written.
void RenderEndEffectorPaths(const std::string& path,
                            const std::vector<PlanProblemPicture>& pictures);

}  // namespace foresight::manipulation
