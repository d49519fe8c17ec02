// Fuzz target: the LibTorch checkpoint reader (training/trainer.h LoadCheckpointModel) against
// damaged files. The input is a checkpoint file as it lies on disk: LibTorch's archive followed by
// the 16-byte trailer "FSCKPT01" + FNV-1a of the archive (training/trainer.cc). The seeds are valid
// checkpoints of a Linear(3, 2) with Adam (docs/robustness.md); every mutation of them (bit flips,
// truncation, deletions, splices: a damaged disk or an interrupted copy) must be refused with one
// line naming the file, never reach LibTorch's reader. A crafted archive with a matching checksum
// is out of scope: LibTorch 1.13's reader is not hardened (docs/robustness.md). With LibTorch only:
// driven by fuzz_main.cc's mutations (scripts/fuzz.sh), not by libFuzzer (the fuzz build is
// LibTorch-free).

#include <torch/torch.h>

#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_util.h"
#include "training/trainer.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = foresight::fuzz::WriteScratch("last.pt", data, size);
  torch::nn::Linear module(torch::nn::LinearOptions(3, 2));
  foresight::fuzz::ExpectCleanError(path,
                                    [&] { foresight::LoadCheckpointModel(path, module.get()); });
  return 0;
}
