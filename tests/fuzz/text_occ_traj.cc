// Fuzz target of the Occ-Traj120 readers (datasets/occ_traj.h). The first byte picks the reader
// (even: ReadOccTrajMap, free size and then 40 x 40; odd: ReadOccTrajTrajectories on a fixed
// 40 x 40 map with an occupied block, with both bad-waypoint policies); the rest is the file.
#include <cstddef>
#include <cstdint>

#include "datasets/occ_traj.h"
#include "tests/fuzz/fuzz_util.h"

namespace {
foresight::BinaryGrid FixedMap() {
  foresight::BinaryGrid map(40, 40);
  for (int y = 10; y < 20; ++y)
    for (int x = 15; x < 25; ++x) map.cells[static_cast<std::size_t>(y) * 40 + x] = 1;
  return map;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  namespace ot = foresight::otnet;
  if (data[0] % 2 == 0) {
    const std::string path = foresight::fuzz::WriteScratch("occtraj_1_map.txt", data + 1, size - 1);
    foresight::fuzz::ExpectCleanError(path, [&] { (void)ot::ReadOccTrajMap(path); });
    foresight::fuzz::ExpectCleanError(path, [&] { (void)ot::ReadOccTrajMap(path, 40, 40); });
  } else {
    static const foresight::BinaryGrid map = FixedMap();
    const std::string path =
        foresight::fuzz::WriteScratch("occtraj_1_trajs.txt", data + 1, size - 1);
    for (const ot::BadWaypointPolicy policy :
         {ot::BadWaypointPolicy::kError, ot::BadWaypointPolicy::kDrop}) {
      foresight::fuzz::ExpectCleanError(path, [&] {
        ot::ReadReport report;
        (void)ot::ReadOccTrajTrajectories(path, map, policy, &report);
      });
    }
  }
  return 0;
}
