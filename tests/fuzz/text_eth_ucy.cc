// Fuzz target of the ETH/UCY text reader (datasets/eth_ucy.h): the input is the file.
#include <cstddef>
#include <cstdint>

#include "datasets/eth_ucy.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = foresight::fuzz::WriteScratch("eth_ucy.txt", data, size);
  foresight::fuzz::ExpectCleanError(path, [&] {
    foresight::EthUcyReadStats stats;
    (void)foresight::ReadEthUcy(path, 0.4, &stats);
  });
  return 0;
}
