#include "datasets/tracks.h"

namespace foresight {
std::size_t TrackSet::NumPoints() const {
  std::size_t n = 0;
  for (const auto& t : tracks) n += t.time.size();
  return n;
}
}  // namespace foresight
