// Fuzz target of the directional-sample readers (datasets/directional.h). The first byte picks the
// reader (even: ReadDirectionalGridCsv, odd: ReadEdinburghTracks); the rest is the file.
#include <cstddef>
#include <cstdint>

#include "datasets/directional.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool edinburgh = data[0] % 2 == 1;
  const std::string path =
      foresight::fuzz::WriteScratch(edinburgh ? "tracks.fuzz.txt" : "grid.csv", data + 1, size - 1);
  foresight::fuzz::ExpectCleanError(path, [&] {
    foresight::DirectionalReadStats stats;
    if (edinburgh)
      (void)foresight::ReadEdinburghTracks(path, foresight::HeadingFilter{}, &stats);
    else
      (void)foresight::ReadDirectionalGridCsv(path, &stats);
  });
  return 0;
}
