// Fuzz target of the URDF robot readers. The input is split at 0x00 bytes into up to three parts:
// URDF text, spheres CSV and SRDF text (a missing part is empty; an empty SRDF is not passed, as
// the API allows: no disabled pairs). RobotModel::Load (inference/manipulation/robot_model.h)
// reads all three; SerialChain::Load (inference/imitation/serial_chain.h) reads the URDF from
// link "link1" to link "hand" with two body points.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "inference/imitation/serial_chain.h"
#include "inference/manipulation/robot_model.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace fz = foresight::fuzz;
  std::vector<std::size_t> cuts;  // begin offsets of the parts
  std::vector<std::size_t> ends;
  std::size_t begin = 0;
  for (std::size_t i = 0; i < size && cuts.size() < 2; ++i) {
    if (data[i] == 0) {
      cuts.push_back(begin);
      ends.push_back(i);
      begin = i + 1;
    }
  }
  cuts.push_back(begin);
  ends.push_back(size);
  while (cuts.size() < 3) {
    cuts.push_back(size);
    ends.push_back(size);
  }
  const std::string urdf = fz::WriteScratch("robot.urdf", data + cuts[0], ends[0] - cuts[0]);
  const std::string spheres = fz::WriteScratch("spheres.csv", data + cuts[1], ends[1] - cuts[1]);
  const bool has_srdf = ends[2] > cuts[2];
  const std::string srdf =
      has_srdf ? fz::WriteScratch("robot.srdf", data + cuts[2], ends[2] - cuts[2]) : std::string();
  // The error names one of the three files; they share the scratch directory.
  const std::string dir = urdf.substr(0, urdf.rfind('/') + 1);
  fz::ExpectCleanError(
      dir, [&] { (void)foresight::manipulation::RobotModel::Load(urdf, spheres, srdf); });
  fz::ExpectCleanError(urdf, [&] {
    std::vector<foresight::imitation::BodyPoint> points(2);
    points[0].link = "link3";
    points[0].offset = {0.0, 0.0, 0.1};
    points[0].radius = 0.05;
    points[1].link = "hand";
    points[1].radius = 0.08;
    (void)foresight::imitation::SerialChain::Load(urdf, "link1", "hand", points);
  });
  return 0;
}
