// Fuzz target of the crowd readers (datasets/crowd_replay.h, datasets/crowd_sim.h). The first byte
// modulo 5 picks the reader: 0 ReadThorTracks, 1 ReadEthObsmat, 2 ReadHomography,
// 3 ReadImplicitCrowdsScenario, 4 ReadImplicitCrowdsParameters; the rest is the file.
#include <cstddef>
#include <cstdint>

#include "datasets/crowd_replay.h"
#include "datasets/crowd_sim.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kNames[] = {"thor.csv", "obsmat.txt", "H.txt", "scenario.txt",
                                       "implicit.ini"};
  const int which = data[0] % 5;
  const std::string path = foresight::fuzz::WriteScratch(kNames[which], data + 1, size - 1);
  foresight::fuzz::ExpectCleanError(path, [&] {
    switch (which) {
      case 0:
        (void)foresight::ReadThorTracks(path);
        break;
      case 1:
        (void)foresight::ReadEthObsmat(path, 0.4);
        break;
      case 2:
        (void)foresight::ReadHomography(path);
        break;
      case 3:
        (void)foresight::ReadImplicitCrowdsScenario(path);
        break;
      default:
        (void)foresight::ReadImplicitCrowdsParameters(path, foresight::PowerLawParams{});
    }
  });
  return 0;
}
