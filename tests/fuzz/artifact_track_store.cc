// Fuzz target: ReadTrackStore (datasets/track_store.h) on edited valid track stores
// (tests/fuzz/h5_mutator.h). A store that loads must hold only finite, increasing tracks.
#include <cmath>

#include "datasets/track_store.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/h5_mutator.h"

namespace {

const std::vector<std::uint8_t>& Base() {
  static const std::vector<std::uint8_t> bytes = [] {
    foresight::TrackSet set;
    set.source = "fuzz";
    set.seconds_per_step = 0.4;
    for (int k = 0; k < 3; ++k) {
      foresight::Track t;
      t.agent_id = 10 + k;
      const int n = 2 + k;
      t.positions.resize(n, 2);
      for (int i = 0; i < n; ++i) {
        t.time.push_back(0.4 * i + k);
        t.positions(i, 0) = 0.5 * i - k;
        t.positions(i, 1) = 0.25 * i * k;
      }
      set.tracks.push_back(std::move(t));
    }
    const std::string path = foresight::fuzz::ScratchPath("base_tracks.h5");
    foresight::WriteTrackStore(path, set);
    return foresight::fuzz::ReadFileBytes(path);
  }();
  return bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace foresight;
  const std::string path = fuzz::WriteScratch("tracks.h5", Base().data(), Base().size());
  fuzz::ByteReader in(data, size);
  fuzz::MutateH5(path, &in);
  fuzz::ExpectCleanError(path, [&] {
    const TrackSet set = ReadTrackStore(path);
    bool finite = std::isfinite(set.seconds_per_step) && set.seconds_per_step > 0;
    for (const Track& t : set.tracks) {
      finite = finite && t.positions.allFinite() && t.positions.rows() == t.size();
      for (double x : t.time) finite = finite && std::isfinite(x);
    }
    fuzz::ExpectFiniteAnswer(finite, path, "a track");
  });
  return 0;
}
