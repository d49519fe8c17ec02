#pragma once
/// Pictures of generated trajectories on maps (PNG, OpenCV): one panel per map, rows of panels.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/binary_grid.h"

namespace foresight::otnet {

struct TrajectoryPanel {
  const BinaryGrid* map = nullptr;
  std::vector<Eigen::MatrixX2d> truth;      ///< drawn thin, blue
  std::vector<Eigen::MatrixX2d> generated;  ///< drawn red, end points marked
  std::vector<Eigen::MatrixX2d> colliding;  ///< samples that were rejected, drawn orange
  bool has_start = false;
  Eigen::Vector2d start = Eigen::Vector2d::Zero();  ///< black marker
  std::string title;
};

/// Draws rows of panels (each row may differ in length) into `png`. Error when it cannot write.
void DrawTrajectoryPanels(const std::vector<std::vector<TrajectoryPanel>>& rows,
                          const std::string& png);

}  // namespace foresight::otnet
