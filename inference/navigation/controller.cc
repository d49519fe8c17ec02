#include "inference/navigation/controller.h"

namespace foresight::nav {

const char* ToString(ControlStatus status) {
  switch (status) {
    case ControlStatus::kSolved:
      return "solved";
    case ControlStatus::kNoFinitePlan:
      return "no_finite_plan";
    case ControlStatus::kNoPath:
      return "no_path";
    case ControlStatus::kError:
      return "error";
  }
  return "";
}

ControlOutcome ControlOutcome::Stop(ControlStatus status, std::string message) {
  ControlOutcome out;
  out.status = status;
  out.message = std::move(message);
  out.command = {0, 0};
  return out;
}

}  // namespace foresight::nav
