#pragma once
/// Reader of the ETH/UCY text format used by Social-GAN and Trajectron++:
/// whitespace-separated `frame_id ped_id x y` (metres), rows sorted by frame.
/// See ../shared/data/eth_ucy/README.md. The frame step (10 in these files) is inferred as the most
/// common positive frame difference of consecutive observations of one pedestrian; one such step
/// is `seconds_per_step` seconds. A pedestrian seen again after a gap starts a new track (counted).

#include <string>

#include "datasets/tracks.h"

namespace foresight {

struct EthUcyReadStats {
  std::size_t rows = 0, pedestrians = 0, tracks = 0, gaps_split = 0;
  long frame_step = 0;
};

/// Reads one file. Malformed input (non-numeric fields, missing columns, NaN/inf, unsorted
/// frames, a pedestrian twice in one frame) is an Error naming file and line.
TrackSet ReadEthUcy(const std::string& path, double seconds_per_step,
                    EthUcyReadStats* stats = nullptr);

}  // namespace foresight
