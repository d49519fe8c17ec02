// Fuzz target: DirectionalMap::Load (spatiotemporal and spatial variants) on edited valid
// artifacts written by DirectionalMap::Save (tests/fuzz/h5_mutator.h); the first input byte picks
// the variant. A map that loads must answer a finite query with a finite mixture.
#include <cmath>

#include "inference/directional/directional_map.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/h5_mutator.h"
#include "tests/inference/directional_test_util.h"

namespace {

std::vector<std::uint8_t> Base(foresight::directional::Variant v) {
  using namespace foresight;
  const bool st = v == directional::Variant::kSpatiotemporal;
  const directional::Map map =
      testing::RandomDirectionalMap(v, testing::SmallFeatureConfig(), 3, 2, st ? 1 : 2);
  const std::string path = fuzz::ScratchPath(st ? "base_dir_st.h5" : "base_dir_s.h5");
  map.Save(path, "model: directional\n", 0);
  return fuzz::ReadFileBytes(path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace foresight;
  static const std::vector<std::uint8_t> bases[] = {Base(directional::Variant::kSpatiotemporal),
                                                    Base(directional::Variant::kSpatial)};
  fuzz::ByteReader in(data, size);
  const int kind = in.Byte() % 2;
  const std::string path = fuzz::WriteScratch("dir.h5", bases[kind].data(), bases[kind].size());
  fuzz::MutateH5(path, &in);
  fuzz::ExpectCleanError(path, [&] {
    const directional::Map map = directional::Map::Load(path);
    auto ws = map.MakeWorkspace();
    map.QueryOne(4.2, 1.3, 20.0, &ws);
    fuzz::ExpectFiniteAnswer(ws.alpha.allFinite() && ws.mu.allFinite() && ws.kappa.allFinite(),
                             path, "the direction mixture");
  });
  return 0;
}
