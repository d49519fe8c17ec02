#pragma once
/// A Franka Emika Panda that needs no data files: for the quickstart, the synthetic problems and
/// the tests of a fresh clone. Kinematics from Franka's published Denavit-Hartenberg table
/// (modified DH: a, d, alpha per joint; flange 0.107 m; hand rotated -pi/4; grasp target 0.105 m
/// below the hand) and joint limits from its datasheet; written here as a URDF. The collision
/// model is our own coarse one: spheres along the segments between joint origins (radius 0.07 m
/// on the arm, 0.06 m on the wrist, 0.05 m on the hand), not the 59-sphere VAMP set of
/// ../shared/data/franka_panda, which the MotionBenchMaker experiments use. Link pairs at most
/// three apart in the chain are not checked for self-collision (their coarse spheres overlap).

#include <string>

#include "inference/manipulation/robot_model.h"

namespace foresight::manipulation {

/// The built-in Panda's URDF, spheres (CSV: link,x,y,z,radius) and SRDF texts.
struct BuiltinPandaDescription {
  std::string urdf, spheres_csv, srdf;
};
BuiltinPandaDescription BuiltinPandaTexts();

/// The built-in Panda as a RobotModel.
RobotModel BuiltinPanda();

}  // namespace foresight::manipulation
