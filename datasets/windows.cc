#include "datasets/windows.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "core/error.h"
#include "core/log.h"

namespace foresight {

WindowSet MakeWindows(const TrackSet& set, const WindowConfig& c) {
  const int len = c.observed + c.predicted;
  const double dt = set.seconds_per_step;
  int count = 0, short_tracks = 0;
  for (const Track& t : set.tracks) {
    if (t.size() >= len)
      count += (t.size() - len) / c.stride + 1;
    else
      ++short_tracks;
  }
  if (short_tracks > 0)
    log::Info(set.source, ": ", short_tracks, " of ", set.tracks.size(),
              " tracks are shorter than ", len, " points and give no window");
  WindowSet w;
  w.seconds_per_step = dt;
  w.observed = c.observed;
  w.predicted = c.predicted;
  w.past.resize(count, 2 * c.observed);
  w.future.resize(count, 2 * c.predicted);
  w.track.reserve(static_cast<std::size_t>(count));
  int k = 0;
  for (std::size_t ti = 0; ti < set.tracks.size(); ++ti) {
    const Track& t = set.tracks[ti];
    for (int s = 0; s + len <= t.size(); s += c.stride) {
      for (int i = 1; i < len; ++i) {
        const double step =
            t.time[static_cast<std::size_t>(s + i)] - t.time[static_cast<std::size_t>(s + i - 1)];
        FS_THROW_UNLESS(std::abs(step - dt) < 1e-6 * std::max(1.0, dt), set.source, ": track ",
                        t.agent_id, " is not sampled every ", dt, " s (step ", step, " s)");
      }
      for (int i = 0; i < c.observed; ++i) {
        w.past(k, 2 * i) = t.positions(s + i, 0);
        w.past(k, 2 * i + 1) = t.positions(s + i, 1);
      }
      for (int i = 0; i < c.predicted; ++i) {
        w.future(k, 2 * i) = t.positions(s + c.observed + i, 0);
        w.future(k, 2 * i + 1) = t.positions(s + c.observed + i, 1);
      }
      w.track.push_back(static_cast<int>(ti));
      ++k;
    }
  }
  return w;
}

WindowSet Concat(const std::vector<WindowSet>& parts) {
  WindowSet out;
  int n = 0;
  for (const auto& p : parts) {
    if (p.size() == 0) continue;
    if (out.observed == 0) {
      out.observed = p.observed;
      out.predicted = p.predicted;
      out.seconds_per_step = p.seconds_per_step;
    }
    FS_THROW_UNLESS(p.observed == out.observed && p.predicted == out.predicted &&
                        std::abs(p.seconds_per_step - out.seconds_per_step) < 1e-9,
                    "cannot concatenate windows of different shapes or steps");
    n += p.size();
  }
  out.past.resize(n, 2 * out.observed);
  out.future.resize(n, 2 * out.predicted);
  int k = 0, track_offset = 0;
  for (const auto& p : parts) {
    if (p.size() == 0) continue;
    out.past.middleRows(k, p.size()) = p.past;
    out.future.middleRows(k, p.size()) = p.future;
    int max_track = 0;
    for (int t : p.track) {
      out.track.push_back(t + track_offset);
      max_track = std::max(max_track, t + 1);
    }
    track_offset += max_track;
    k += p.size();
  }
  return out;
}

TrackSplit SplitTracks(const TrackSet& set, double val_fraction, double test_fraction,
                       std::uint64_t seed) {
  FS_THROW_UNLESS(val_fraction >= 0 && test_fraction >= 0 && val_fraction + test_fraction < 1,
                  "split fractions must be >= 0 and sum to < 1 (val ", val_fraction, ", test ",
                  test_fraction, ")");
  std::vector<std::size_t> order(set.tracks.size());
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  const auto n = order.size();
  const auto n_val = static_cast<std::size_t>(std::llround(val_fraction * static_cast<double>(n)));
  const auto n_test =
      static_cast<std::size_t>(std::llround(test_fraction * static_cast<double>(n)));
  TrackSplit out;
  for (TrackSet* s : {&out.train, &out.val, &out.test}) {
    s->source = set.source;
    s->seconds_per_step = set.seconds_per_step;
  }
  for (std::size_t i = 0; i < n; ++i) {
    TrackSet& dst = i < n_val ? out.val : (i < n_val + n_test ? out.test : out.train);
    dst.tracks.push_back(set.tracks[order[i]]);
  }
  return out;
}

}  // namespace foresight
