#pragma once
/// urdfdom helpers shared by the robot models (the Panda's RobotModel, the JACO's SerialChain):
/// capturing urdfdom's error messages for one-line errors, URDF poses as Eigen isometries, joint
/// type names. Header-only; needs urdfdom and console_bridge.

#include <console_bridge/console.h>
#include <urdf_model/model.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstddef>
#include <mutex>
#include <string>

#include "core/error.h"

namespace foresight::urdf_util {

/// Refuses XML text that is not UTF-8, naming the offending byte. TinyXML (which urdfdom parses
/// with) steps over a multi-byte sequence by its lead byte without checking what follows, so a
/// truncated sequence at the end of the text makes it read past the buffer (found by fuzzing).
inline void CheckUtf8(const std::string& text, const std::string& source) {
  const std::size_t n = text.size();
  for (std::size_t i = 0; i < n;) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t len = c < 0x80           ? 1
                            : (c >> 5) == 0x6  ? 2
                            : (c >> 4) == 0xE  ? 3
                            : (c >> 3) == 0x1E ? 4
                                               : 0;
    bool ok = len > 0 && i + len <= n;
    for (std::size_t k = 1; ok && k < len; ++k)
      ok = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
    FS_THROW_UNLESS(ok, source, ": byte ", i, " (value ", static_cast<int>(c),
                    ") starts no valid UTF-8 character; XML text must be UTF-8");
    i += len;
  }
}

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

/// The urdfdom model of `text` (CheckUtf8 first); an Error naming `source` and urdfdom's reasons
/// when it is not a valid URDF. Pair it with FreeLinkCyclesOnExit.
inline urdf::ModelInterfaceSharedPtr ParseUrdf(const std::string& text, const std::string& source) {
  CheckUtf8(text, source);
  CaptureUrdfdomErrors errors;
  urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(text);
  FS_THROW_UNLESS(urdf != nullptr, source, ": not a valid URDF: ",
                  errors.messages().empty() ? "urdfdom gave no reason" : errors.messages());
  return urdf;
}

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
