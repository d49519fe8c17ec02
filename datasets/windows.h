#pragma once
/// Observation/prediction windows cut from tracks: observe p points, predict the next f.

#include <Eigen/Core>
#include <vector>

#include "core/config.h"
#include "datasets/tracks.h"

namespace foresight {

struct WindowConfig {
  int observed = 8;    ///< p observed points (8 = 3.2 s at 0.4 s)
  int predicted = 12;  ///< f future points (12 = 4.8 s)
  int stride = 1;      ///< step between window starts (points)

  template <class A>
  void Serialize(A* a) {
    a->Visit("observed", &observed, config::Range::AtLeast(2), "observed points per window");
    a->Visit("predicted", &predicted, config::Range::AtLeast(1), "future points per window");
    a->Visit("stride", &stride, config::Range::AtLeast(1), "step between window starts (points)");
  }
};

/// Windows in world coordinates. Row k of `past` is x_1, y_1, ..., x_p, y_p (oldest first);
/// row k of `future` is x_{p+1}, y_{p+1}, ..., x_{p+f}, y_{p+f}.
struct WindowSet {
  double seconds_per_step = 0.4;
  int observed = 0, predicted = 0;
  Eigen::MatrixXd past;    ///< [N x 2p] metres
  Eigen::MatrixXd future;  ///< [N x 2f] metres
  std::vector<int> track;  ///< [N] index of the source track
  int size() const { return static_cast<int>(past.rows()); }
  /// Point i (0-based) of window k's past / future.
  Eigen::Vector2d Past(int k, int i) const { return {past(k, 2 * i), past(k, 2 * i + 1)}; }
  Eigen::Vector2d Future(int k, int i) const { return {future(k, 2 * i), future(k, 2 * i + 1)}; }
};

/// All windows of every track long enough; tracks must be uniformly sampled.
WindowSet MakeWindows(const TrackSet& set, const WindowConfig& config);
/// Concatenates window sets of the same shape and step.
WindowSet Concat(const std::vector<WindowSet>& parts);

/// Splits tracks (not windows) into train / val / test by a seeded shuffle.
struct TrackSplit {
  TrackSet train, val, test;
};
TrackSplit SplitTracks(const TrackSet& set, double val_fraction, double test_fraction,
                       std::uint64_t seed);

}  // namespace foresight
