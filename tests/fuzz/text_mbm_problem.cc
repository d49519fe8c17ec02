// Fuzz target of the MotionBenchMaker readers (inference/manipulation/mbm_problem.h). The first
// byte picks the reader. Even: the rest is split at its first 0x00 byte into the scene YAML and
// the request YAML (no 0x00: the request is empty), read by LoadMbmProblem. Odd: the rest is a
// compact JSON family, read by LoadCompactFamily for problems 1..2.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "inference/manipulation/mbm_problem.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  namespace fz = foresight::fuzz;
  const std::uint8_t* rest = data + 1;
  const std::size_t n = size - 1;
  if (data[0] % 2 == 0) {
    const void* zero = n ? std::memchr(rest, 0, n) : nullptr;
    const std::size_t scene_size =
        zero ? static_cast<std::size_t>(static_cast<const std::uint8_t*>(zero) - rest) : n;
    const std::size_t request_at = zero ? scene_size + 1 : n;
    const std::string scene = fz::WriteScratch("scene0001.yaml", rest, scene_size);
    const std::string request =
        fz::WriteScratch("request0001.yaml", rest + request_at, n - request_at);
    // The error names the scene or the request file; both share the scratch directory.
    const std::string dir = scene.substr(0, scene.rfind('/') + 1);
    fz::ExpectCleanError(dir,
                         [&] { (void)foresight::manipulation::LoadMbmProblem(scene, request); });
  } else {
    const std::string path = fz::WriteScratch("family.json", rest, n);
    fz::ExpectCleanError(path,
                         [&] { (void)foresight::manipulation::LoadCompactFamily(path, 1, 2); });
  }
  return 0;
}
