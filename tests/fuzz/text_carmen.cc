// Fuzz target of the CARMEN log reader (datasets/carmen.h): the input is the log.
// Both option settings (constant beam count required or not) run on every input.
#include <cstddef>
#include <cstdint>

#include "datasets/carmen.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = foresight::fuzz::WriteScratch("carmen.log", data, size);
  for (const bool same : {true, false}) {
    foresight::fuzz::ExpectCleanError(path, [&] {
      foresight::CarmenReadOptions options;
      options.require_constant_beam_count = same;
      (void)foresight::ReadCarmenLog(path, options);
    });
  }
  return 0;
}
