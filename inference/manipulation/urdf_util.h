#pragma once
/// urdfdom helpers shared by the robot models (the Panda's RobotModel, the JACO's SerialChain):
/// capturing urdfdom's error messages for one-line errors, URDF poses as Eigen isometries, joint
/// type names. Header-only; needs urdfdom and console_bridge.

#include <console_bridge/console.h>
#include <urdf_model/model.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <mutex>
#include <string>

namespace foresight::urdf_util {

/// While alive, collects urdfdom's error messages (console_bridge) instead of printing them, so
/// that a failed parse can say why. console_bridge's handler is global: one capture at a time.
class CaptureUrdfdomErrors : public console_bridge::OutputHandler {
 public:
  CaptureUrdfdomErrors() : lock_(Mutex()) { console_bridge::useOutputHandler(this); }
  ~CaptureUrdfdomErrors() override { console_bridge::restorePreviousOutputHandler(); }
  CaptureUrdfdomErrors(const CaptureUrdfdomErrors&) = delete;
  CaptureUrdfdomErrors& operator=(const CaptureUrdfdomErrors&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level, const char* /*filename*/,
           int /*line*/) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_ERROR) return;
    std::string one_line = text;  // error messages are one line
    std::replace(one_line.begin(), one_line.end(), '\n', ' ');
    std::replace(one_line.begin(), one_line.end(), '\r', ' ');
    while (!one_line.empty() && one_line.back() == ' ') one_line.pop_back();
    messages_ += (messages_.empty() ? "" : "; ") + one_line;
  }
  const std::string& messages() const { return messages_; }

 private:
  static std::mutex& Mutex() {
    static std::mutex mutex;
    return mutex;
  }
  std::lock_guard<std::mutex> lock_;
  std::string messages_;
};

/// Frees a parsed model when it goes out of scope even if its links form a loop: urdfdom links own
/// their children (shared_ptr), and urdfdom accepts a loop of joints that is not connected to the
/// root, which then is a reference cycle (a leak). Clears every link's child lists on destruction;
/// use it where the model is parsed and drop the model with it.
class FreeLinkCyclesOnExit {
 public:
  explicit FreeLinkCyclesOnExit(const urdf::ModelInterfaceSharedPtr& model) : model_(model) {}
  ~FreeLinkCyclesOnExit() {
    if (!model_) return;
    for (auto& [name, link] : model_->links_) {
      if (!link) continue;
      link->child_links.clear();
      link->child_joints.clear();
    }
  }
  FreeLinkCyclesOnExit(const FreeLinkCyclesOnExit&) = delete;
  FreeLinkCyclesOnExit& operator=(const FreeLinkCyclesOnExit&) = delete;

 private:
  const urdf::ModelInterfaceSharedPtr& model_;
};

inline Eigen::Isometry3d ToIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() =
      Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z)
          .normalized()
          .toRotationMatrix();
  X.translation() << pose.position.x, pose.position.y, pose.position.z;
  return X;
}

inline const char* JointTypeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE:
      return "revolute";
    case urdf::Joint::CONTINUOUS:
      return "continuous";
    case urdf::Joint::PRISMATIC:
      return "prismatic";
    case urdf::Joint::FLOATING:
      return "floating";
    case urdf::Joint::PLANAR:
      return "planar";
    case urdf::Joint::FIXED:
      return "fixed";
    default:
      return "unknown";
  }
}

}  // namespace foresight::urdf_util
