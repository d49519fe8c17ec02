// Fuzz target of the LASA handwriting reader (datasets/lasa.h): the input is the shape's CSV,
// written as <scratch>/lasa/csv/Fuzz.csv and read as shape "Fuzz" of the directory <scratch>/lasa.
#include <cstddef>
#include <cstdint>
#include <filesystem>

#include "datasets/lasa.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string dir = [] {
    const std::string d = foresight::fuzz::ScratchPath("lasa");
    std::filesystem::create_directories(d + "/csv");
    return d;
  }();
  const std::string path = foresight::fuzz::WriteScratch("lasa/csv/Fuzz.csv", data, size);
  foresight::fuzz::ExpectCleanError(path, [&] { (void)foresight::ReadLasaShape(dir, "Fuzz"); });
  return 0;
}
