#pragma once
/// The check every config applies to a list of hidden-layer widths before a network is built.

#include <cstddef>
#include <string>
#include <vector>

#include "core/error.h"

namespace foresight {

/// `widths` (config key `key` of `source`) lists 1 to 16 layers of 1 to 65536 units with at most
/// 5e7 hidden-to-hidden weights (200 MB of floats before the optimiser's moments): a network of
/// this size no longer runs in real time on a CPU, and a typo (an extra digit, a 10 M-entry list)
/// stops here with the key named instead of exhausting memory in the model constructor.
inline void CheckLayerWidths(const std::vector<int>& widths, const std::string& source,
                             const std::string& key) {
  constexpr std::size_t kMaxLayers = 16;
  constexpr double kMaxWeights = 5e7;
  FS_THROW_UNLESS(!widths.empty(), source, ": ", key, ": empty (give at least one layer width)");
  FS_THROW_UNLESS(widths.size() <= kMaxLayers, source, ": ", key, ": ", widths.size(),
                  " layers, more than ", kMaxLayers);
  double weights = 0;
  for (std::size_t i = 0; i < widths.size(); ++i) {
    FS_THROW_UNLESS(widths[i] >= 1 && widths[i] <= 65536, source, ": ", key, "[", i,
                    "]: ", widths[i], " is outside [1, 65536]");
    if (i > 0) weights += static_cast<double>(widths[i - 1]) * widths[i];
  }
  FS_THROW_UNLESS(weights <= kMaxWeights, source, ": ", key, ": ", weights,
                  " hidden-to-hidden weights, more than ", kMaxWeights);
}

}  // namespace foresight
