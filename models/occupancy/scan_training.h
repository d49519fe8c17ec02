#pragma once
/// Sequential training of a scan-by-scan map learner (Fast-BHM, BHM) on labelled points.

#include <algorithm>
#include <vector>

#include "datasets/occupancy_points.h"

namespace foresight::occupancy {

/// Feeds the listed scans of `points` to `learner->Update(xy, occupied)`, in the given order.
template <class Learner>
void UpdateOnScans(Learner* learner, const LabelledPoints& points, const std::vector<int>& scans) {
  for (const int s : scans) {
    const auto b = points.scan_begin[s], e = points.scan_begin[s + 1];
    learner->Update(points.xy.middleCols(b, e - b), points.occupied.data() + b);
  }
}

/// The first `count` scans of `points` (all when count < 0), in order.
inline std::vector<int> FirstScans(const LabelledPoints& points, int count = -1) {
  const int n = count < 0 ? points.num_scans() : std::min(count, points.num_scans());
  std::vector<int> s(n);
  for (int i = 0; i < n; ++i) s[i] = i;
  return s;
}

}  // namespace foresight::occupancy
