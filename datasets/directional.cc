#include "datasets/directional.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <random>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"
#include "core/portable_random.h"
#include "core/von_mises.h"

namespace foresight {
namespace {

/// Growable columns, turned into DirectionalSamples at the end.
struct SampleColumns {
  std::vector<double> x, y, t, theta;
  std::vector<std::int64_t> path;
  void Add(double xi, double yi, double ti, double thetai, std::int64_t path_id) {
    x.push_back(xi);
    y.push_back(yi);
    t.push_back(ti);
    theta.push_back(thetai);
    path.push_back(path_id);
  }
  DirectionalSamples Finish() const {
    DirectionalSamples s;
    const auto n = static_cast<Eigen::Index>(x.size());
    s.x = Eigen::Map<const Eigen::VectorXd>(x.data(), n);
    s.y = Eigen::Map<const Eigen::VectorXd>(y.data(), n);
    s.t = Eigen::Map<const Eigen::VectorXd>(t.data(), n);
    s.theta = Eigen::Map<const Eigen::VectorXd>(theta.data(), n);
    s.path = path;
    return s;
  }
};

void LogStats(const std::string& path, const DirectionalReadStats& s) {
  log::Info(path, ": ", s.kept, " direction samples from ", s.points, " points in ", s.tracks,
            " tracks (no heading at ", s.first_points, " track starts; dropped ",
            s.dropped_standing, " standing, ", s.dropped_jump, " jumps, ", s.dropped_gap,
            " after gaps, ", s.dropped_short_track, " in short tracks)");
}

std::string Trim(const std::string& text) {
  const auto b = text.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = text.find_last_not_of(" \t\r\n");
  return text.substr(b, e - b + 1);
}

std::vector<std::string> SplitComma(const std::string& text) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(text);
  while (std::getline(in, field, ',')) out.push_back(Trim(field));
  if (!text.empty() && text.back() == ',') out.emplace_back();
  return out;
}

/// One parsed Edinburgh point (pixels, frame number).
struct PixelPoint {
  double x = 0, y = 0;
  long long frame = 0;
};

/// Parses " TRACK.R<id>=[[x y f];[x y f];...;[x y f]];" into points; errors name path:line.
std::vector<PixelPoint> ParseTrackLine(const std::string& text, const std::string& where,
                                       std::string* id) {
  const auto eq = text.find('=');
  FS_THROW_UNLESS(eq != std::string::npos, where, ": TRACK line without '='");
  *id = Trim(text.substr(0, eq)).substr(6);  // after "TRACK."
  const std::string body = Trim(text.substr(eq + 1));
  FS_THROW_UNLESS(body.size() >= 5 && body.compare(0, 2, "[[") == 0 &&
                      body.compare(body.size() - 3, 3, "]];") == 0,
                  where, ": TRACK.", *id, " must look like [[x y t];...;[x y t]]; (got '",
                  body.substr(0, 40), body.size() > 40 ? "...'" : "'", ")");
  const std::string inner = body.substr(2, body.size() - 5);  // "x y t];[x y t];...;[x y t"
  std::vector<PixelPoint> points;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = inner.find("];[", start);
    const std::string item =
        inner.substr(start, end == std::string::npos ? std::string::npos : end - start);
    std::istringstream fields(item);
    std::vector<std::string> f;
    for (std::string w; fields >> w;) f.push_back(w);
    const std::size_t k = points.size() + 1;
    FS_THROW_UNLESS(f.size() == 3, where, ": TRACK.", *id, " point ", k, " '", item,
                    "' must be 'x y frame'");
    const std::optional<double> x = ParseDouble(f[0]), y = ParseDouble(f[1]);
    const std::optional<long long> frame = ParseInteger(f[2]);
    FS_THROW_UNLESS(x && y && std::isfinite(*x) && std::isfinite(*y), where, ": TRACK.", *id,
                    " point ", k, " '", item, "' has a non-numeric or non-finite coordinate");
    FS_THROW_UNLESS(frame.has_value(), where, ": TRACK.", *id, " point ", k, " '", item,
                    "' has a frame that is not an integer");
    FS_THROW_UNLESS(points.empty() || *frame >= points.back().frame, where, ": TRACK.", *id,
                    " point ", k, " goes back in time (frame ", *frame, " after ",
                    points.back().frame, ")");
    points.push_back({*x, *y, *frame});
    if (end == std::string::npos) break;
    start = end + 3;
  }
  return points;
}

}  // namespace

DirectionalSamples DirectionalSamples::Select(const std::vector<Eigen::Index>& index) const {
  DirectionalSamples s;
  const auto n = static_cast<Eigen::Index>(index.size());
  s.x.resize(n);
  s.y.resize(n);
  s.t.resize(n);
  s.theta.resize(n);
  const bool has_path = !path.empty();
  if (has_path) s.path.resize(index.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index j = index[static_cast<std::size_t>(i)];
    FS_THROW_UNLESS(j >= 0 && j < size(), "DirectionalSamples::Select: row ", j, " is outside [0, ",
                    size(), ")");
    s.x[i] = x[j];
    s.y[i] = y[j];
    s.t[i] = t[j];
    s.theta[i] = theta[j];
    if (has_path) {
      FS_THROW_UNLESS(static_cast<std::size_t>(j) < path.size(), "DirectionalSamples::Select: row ",
                      j, " has no path id (path [", path.size(), "], x [", size(), "])");
      s.path[static_cast<std::size_t>(i)] = path[static_cast<std::size_t>(j)];
    }
  }
  return s;
}

void DirectionalSamples::Validate(const std::string& where) const {
  FS_THROW_UNLESS(y.size() == x.size() && t.size() == x.size() && theta.size() == x.size(), where,
                  ": direction samples have x [", x.size(), "], y [", y.size(), "], t [", t.size(),
                  "], theta [", theta.size(), "] (sizes must match)");
  FS_THROW_UNLESS(size() > 0, where, ": no direction samples");
  FS_THROW_UNLESS(path.empty() || static_cast<Eigen::Index>(path.size()) == size(), where,
                  ": path ids [", path.size(), "] must be empty or one per sample [", size(), "]");
  for (Eigen::Index i = 0; i < size(); ++i) {
    FS_THROW_UNLESS(std::isfinite(x[i]) && std::isfinite(y[i]) && std::isfinite(t[i]) &&
                        std::isfinite(theta[i]),
                    where, ": direction sample ", i, " (x ", x[i], ", y ", y[i], ", t ", t[i],
                    ", theta ", theta[i], ") is not finite");
    FS_THROW_UNLESS(theta[i] >= -M_PI && theta[i] < M_PI, where, ": direction sample ", i,
                    " has theta ", theta[i], " outside [-pi, pi)");
  }
}

DirectionalSamples ReadDirectionalGridCsv(const std::string& path,
                                          DirectionalReadStats* stats_out) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open directional grid csv");
  static const char* kHeader = "x_m,y_m,orientation_raw_rad,path_id";
  std::string text;
  std::size_t line = 1;
  FS_THROW_UNLESS(std::getline(in, text) && Trim(text) == kHeader, path,
                  ":1: expected the header '", kHeader, "', got '", Trim(text), "'");

  DirectionalReadStats stats;
  SampleColumns out;
  std::set<long long> finished_paths;
  long long path_id = -1, row_in_path = 0;
  std::int64_t segment = -1;  // output path id: one per drawn path, a new one after a jump
  double px = 0, py = 0;      // previous row of the same path
  while (std::getline(in, text)) {
    ++line;
    if (Trim(text).empty()) continue;
    const std::vector<std::string> f = SplitComma(Trim(text));
    FS_THROW_UNLESS(f.size() == 4, path, ":", line, ": expected 4 comma-separated fields (",
                    kHeader, "), got ", f.size());
    double v[3];
    static const char* kNames[3] = {"x_m", "y_m", "orientation_raw_rad"};
    for (int c = 0; c < 3; ++c) {
      const std::optional<double> d = ParseDouble(f[static_cast<std::size_t>(c)]);
      FS_THROW_UNLESS(d.has_value(), path, ":", line, ": ", kNames[c], " is not a number: '",
                      f[static_cast<std::size_t>(c)], "'");
      FS_THROW_UNLESS(std::isfinite(*d), path, ":", line, ": ", kNames[c], " is not finite: '",
                      f[static_cast<std::size_t>(c)], "'");
      v[c] = *d;
    }
    // np.savetxt wrote the integer ids as floats ("0", "1", or "1e+01" with %.10g).
    const std::optional<double> id = ParseDouble(f[3]);
    FS_THROW_UNLESS(id && *id >= 0 && *id == std::floor(*id) && *id < 1e15, path, ":", line,
                    ": path_id is not a non-negative integer: '", f[3], "'");
    const auto pid = static_cast<long long>(*id);
    ++stats.points;
    if (pid != path_id) {
      FS_THROW_UNLESS(finished_paths.count(pid) == 0, path, ":", line, ": path_id ", pid,
                      " appears again after other paths (rows must be grouped by path)");
      if (path_id >= 0) finished_paths.insert(path_id);
      path_id = pid;
      row_in_path = 0;
      ++segment;
      ++stats.tracks;
      // The first row of a path has a placeholder (0) or a heading computed across the previous
      // path's last point: no heading.
      ++stats.first_points;
    } else {
      ++row_in_path;
      const double dx = v[0] - px, dy = v[1] - py, step = std::hypot(dx, dy);
      if (step == 0) {
        // Repeated way-point: the file's orientation is atan2(0, 0) + pi/2, not a heading.
        ++stats.dropped_standing;
      } else if (step > kDirectionalGridMaxStep) {
        ++stats.dropped_jump;
        ++segment;  // the rows after the jump are another walk
      } else {
        // README convention: orientation_raw = pi/2 + atan2(y_prev - y, x_prev - x), so the heading
        // of motion is orientation_raw + pi/2 (mod 2 pi). Checked against the step direction.
        const double heading = WrapAngle(v[2] + M_PI / 2);
        const double mismatch = std::abs(WrapAngle(heading - std::atan2(dy, dx)));
        FS_THROW_UNLESS(mismatch < 1e-4, path, ":", line, ": orientation_raw_rad ", v[2],
                        " gives heading ", heading,
                        " (orientation + pi/2) but the step from the "
                        "previous row points at ",
                        std::atan2(dy, dx), " (", mismatch,
                        " rad apart): not the README convention");
        out.Add(v[0], v[1], static_cast<double>(row_in_path) * kDirectionalGridSecondsPerRow,
                heading, segment);
        ++stats.kept;
      }
    }
    px = v[0];
    py = v[1];
  }
  FS_THROW_UNLESS(stats.points > 0, path, ": no data rows after the header");
  FS_THROW_UNLESS(stats.kept > 0, path, ": no direction samples in ", stats.points, " rows");
  LogStats(path, stats);
  if (stats_out) *stats_out = stats;
  DirectionalSamples s = out.Finish();
  s.Validate(path);
  return s;
}

DirectionalSamples ReadEdinburghTracks(const std::string& path, const HeadingFilter& filter,
                                       DirectionalReadStats* stats_out) {
  FS_THROW_UNLESS(filter.min_speed >= 0 && filter.max_speed > filter.min_speed &&
                      filter.max_gap > 0 && filter.min_track_points >= 2,
                  "heading filter: need 0 <= min_speed < max_speed, max_gap > 0 and "
                  "min_track_points >= 2 (min_speed ",
                  filter.min_speed, ", max_speed ", filter.max_speed, ", max_gap ", filter.max_gap,
                  ", min_track_points ", filter.min_track_points, ")");
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open Edinburgh tracks file");

  struct Track {
    std::vector<PixelPoint> points;
    std::size_t line = 0;
  };
  std::vector<Track> tracks;
  // Properties.R<id>=[n_points start_frame end_frame ...]; checked against the track when present.
  std::map<std::string, std::array<long long, 3>> properties;
  std::string text;
  std::size_t line = 0;
  while (std::getline(in, text)) {
    ++line;
    const std::string trimmed = Trim(text);
    if (trimmed.empty() || trimmed[0] == '%') continue;
    const std::string where = path + ":" + std::to_string(line);
    if (trimmed.rfind("Properties.", 0) == 0) {
      const auto eq = trimmed.find("=[");
      FS_THROW_UNLESS(eq != std::string::npos, where, ": Properties line without '=['");
      std::istringstream values(trimmed.substr(eq + 2));
      std::string a, b, c;
      values >> a >> b >> c;
      const auto n = ParseInteger(a), s = ParseInteger(b), e = ParseInteger(c);
      FS_THROW_UNLESS(n && s && e, where,
                      ": Properties must start with 'n_points start_frame "
                      "end_frame', got '",
                      a, " ", b, " ", c, "'");
      properties[trimmed.substr(11, eq - 11)] = {*n, *s, *e};
      continue;
    }
    FS_THROW_UNLESS(trimmed.rfind("TRACK.", 0) == 0, where,
                    ": expected a comment (%), Properties.R<k>=[...] or TRACK.R<k>=[[...]]; line, "
                    "got '",
                    trimmed.substr(0, 40), "'");
    std::string id;
    Track track;
    track.points = ParseTrackLine(trimmed, where, &id);
    track.line = line;
    if (const auto it = properties.find(id); it != properties.end()) {
      const auto& [n, s, e] = it->second;
      FS_THROW_UNLESS(n == static_cast<long long>(track.points.size()) &&
                          s == track.points.front().frame && e == track.points.back().frame,
                      where, ": TRACK.", id, " has ", track.points.size(), " points in frames ",
                      track.points.front().frame, "..", track.points.back().frame,
                      " but Properties.", id, " says ", n, " points in frames ", s, "..", e);
    }
    tracks.push_back(std::move(track));
  }
  FS_THROW_UNLESS(!tracks.empty(), path, ": no TRACK lines in ", line, " lines");

  long long frame0 = tracks.front().points.front().frame;
  for (const Track& tr : tracks) frame0 = std::min(frame0, tr.points.front().frame);

  DirectionalReadStats stats;
  SampleColumns out;
  const double s = kEdinburghMetresPerPixel;
  std::int64_t segment = -1;  // output path id: one per kept track, a new one after each gap
  for (const Track& tr : tracks) {
    const auto n = static_cast<std::int64_t>(tr.points.size());
    stats.points += n;
    ++stats.tracks;
    if (n < filter.min_track_points) {
      stats.dropped_short_track += n;
      continue;
    }
    ++stats.first_points;
    ++segment;
    for (std::size_t i = 1; i < tr.points.size(); ++i) {
      const PixelPoint& a = tr.points[i - 1];
      const PixelPoint& b = tr.points[i];
      // Pixels (y down) -> metres in a right-handed frame with y up, origin at the bottom-left
      // pixel; frames -> seconds since the earliest frame of the file at the nominal rate.
      const double dx = (b.x - a.x) * s, dy = -(b.y - a.y) * s;
      // Frame differences in double: frames anywhere in the long long range must not overflow.
      const double dt =
          (static_cast<double>(b.frame) - static_cast<double>(a.frame)) / kEdinburghFramesPerSecond;
      if (dt > filter.max_gap) {
        ++stats.dropped_gap;  // starts a new segment: the step across the gap is not a heading
        ++segment;
        continue;
      }
      if (dt <= 0) {
        ++stats.dropped_jump;  // two detections in one frame
        continue;
      }
      const double speed = std::hypot(dx, dy) / dt;
      if (speed > filter.max_speed) {
        ++stats.dropped_jump;
      } else if (speed < filter.min_speed || (dx == 0 && dy == 0)) {
        ++stats.dropped_standing;
      } else {
        out.Add(b.x * s, (kEdinburghImageHeight - 1 - b.y) * s,
                (static_cast<double>(b.frame) - static_cast<double>(frame0)) /
                    kEdinburghFramesPerSecond,
                WrapAngle(std::atan2(dy, dx)), segment);
        ++stats.kept;
      }
    }
  }
  FS_THROW_UNLESS(stats.kept > 0, path, ": no direction samples left of ", stats.points,
                  " points in ", stats.tracks, " tracks after filtering");
  LogStats(path, stats);
  if (stats_out) *stats_out = stats;
  DirectionalSamples samples = out.Finish();
  samples.Validate(path);
  return samples;
}

DirectionalSamples GenerateCrossingFlow(const CrossingFlowConfig& c) {
  FS_THROW_UNLESS(c.num_tracks > 0 && c.duration > 0 && c.size > 0 && c.speed > 0 &&
                      c.sample_period > 0 && c.heading_noise >= 0 && c.dominant_fraction >= 0.5 &&
                      c.dominant_fraction <= 1,
                  "crossing flow: need num_tracks, duration, size, speed, sample_period > 0, "
                  "heading_noise >= 0 and dominant_fraction in [0.5, 1] (num_tracks ",
                  c.num_tracks, ", duration ", c.duration, ", size ", c.size, ", speed ", c.speed,
                  ", sample_period ", c.sample_period, ", heading_noise ", c.heading_noise,
                  ", dominant_fraction ", c.dominant_fraction, ")");
  std::mt19937_64 rng(c.seed);
  const double crossing_time = c.size / c.speed;
  const double step = c.speed * c.sample_period;
  const int max_steps = static_cast<int>(std::ceil(3.0 * crossing_time / c.sample_period)) + 1;
  SampleColumns out;
  for (int k = 0; k < c.num_tracks; ++k) {
    const double t0 = Uniform01(&rng) * std::max(0.0, c.duration - crossing_time);
    // Dominant direction: +x while the track's middle is in the first half of [0, duration],
    // -x in the second half; a (1 - dominant_fraction) share goes the other way.
    const bool first_half = t0 + 0.5 * crossing_time < 0.5 * c.duration;
    const double dominant = first_half ? 1.0 : -1.0;
    const double dir = Uniform01(&rng) < c.dominant_fraction ? dominant : -dominant;
    const double y0 = c.size * (0.1 + 0.8 * Uniform01(&rng));
    const double y1 = c.size * (0.1 + 0.8 * Uniform01(&rng));
    const double goal_x = dir > 0 ? c.size : 0.0;
    double x = dir > 0 ? 0.0 : c.size, y = y0, t = t0;
    for (int i = 0; i < max_steps; ++i) {
      // Steer at the goal on the far side, with independent heading noise per step.
      const double heading =
          std::atan2(y1 - y, goal_x - x) + c.heading_noise * StandardNormal(&rng);
      x += step * std::cos(heading);
      y += step * std::sin(heading);
      t += c.sample_period;
      if (x < 0 || x > c.size || y < 0 || y > c.size || t > c.duration) break;
      out.Add(x, y, t, WrapAngle(heading), k);
    }
  }
  DirectionalSamples s = out.Finish();
  s.Validate("crossing flow");
  return s;
}

std::vector<std::vector<Eigen::Index>> KFoldTestIndices(Eigen::Index n, int k, std::uint64_t seed) {
  FS_THROW_UNLESS(k >= 2 && n >= k, "k-fold split: need k >= 2 folds and at least k rows (k ", k,
                  ", rows ", n, ")");
  std::vector<Eigen::Index> perm(static_cast<std::size_t>(n));
  std::iota(perm.begin(), perm.end(), Eigen::Index{0});
  std::mt19937_64 rng(seed);
  for (std::size_t i = perm.size() - 1; i > 0; --i) std::swap(perm[i], perm[rng() % (i + 1)]);
  std::vector<std::vector<Eigen::Index>> folds(static_cast<std::size_t>(k));
  for (int f = 0; f < k; ++f) {
    const auto begin = static_cast<std::ptrdiff_t>(n * f / k),
               end = static_cast<std::ptrdiff_t>(n * (f + 1) / k);
    folds[static_cast<std::size_t>(f)].assign(perm.begin() + begin, perm.begin() + end);
    std::sort(folds[static_cast<std::size_t>(f)].begin(), folds[static_cast<std::size_t>(f)].end());
  }
  return folds;
}

std::vector<std::vector<Eigen::Index>> GroupedKFoldTestIndices(
    const std::vector<std::int64_t>& groups, int k, std::uint64_t seed) {
  // Rows of each distinct id, ids in increasing order (independent of the row order).
  std::map<std::int64_t, std::vector<Eigen::Index>> rows_of;
  for (std::size_t i = 0; i < groups.size(); ++i)
    rows_of[groups[i]].push_back(static_cast<Eigen::Index>(i));
  FS_THROW_UNLESS(k >= 2 && rows_of.size() >= static_cast<std::size_t>(k),
                  "grouped k-fold split: need k >= 2 folds and at least k groups (k ", k,
                  ", groups ", rows_of.size(), ", rows ", groups.size(), ")");
  std::vector<const std::vector<Eigen::Index>*> order;
  order.reserve(rows_of.size());
  for (const auto& [id, rows] : rows_of) order.push_back(&rows);
  // Shuffle (same draws as KFoldTestIndices), then largest first; equal sizes keep the shuffle.
  std::mt19937_64 rng(seed);
  for (std::size_t i = order.size() - 1; i > 0; --i) std::swap(order[i], order[rng() % (i + 1)]);
  std::stable_sort(order.begin(), order.end(),
                   [](const auto* a, const auto* b) { return a->size() > b->size(); });
  std::vector<std::vector<Eigen::Index>> folds(static_cast<std::size_t>(k));
  for (const std::vector<Eigen::Index>* rows : order) {
    std::size_t smallest = 0;
    for (std::size_t f = 1; f < folds.size(); ++f)
      if (folds[f].size() < folds[smallest].size()) smallest = f;
    folds[smallest].insert(folds[smallest].end(), rows->begin(), rows->end());
  }
  for (auto& fold : folds) std::sort(fold.begin(), fold.end());
  return folds;
}

}  // namespace foresight
