#include "datasets/eth_ucy.h"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"

namespace foresight {
namespace {

struct Row {
  double frame;
  std::int64_t ped;
  double x, y;
};

double ParseField(const std::string& token, const std::string& path, std::size_t line,
                  const char* column) {
  const std::optional<double> parsed = ParseDouble(token);
  FS_THROW_UNLESS(parsed.has_value(), path, ":", line, ": column '", column, "' is not a number: '",
                  token, "'");
  const double v = *parsed;
  FS_THROW_UNLESS(std::isfinite(v), path, ":", line, ": column '", column, "' is not finite: '",
                  token, "'");
  return v;
}

}  // namespace

TrackSet ReadEthUcy(const std::string& path, double seconds_per_step, EthUcyReadStats* stats_out) {
  FS_THROW_UNLESS(seconds_per_step > 0, "ReadEthUcy: seconds_per_step must be > 0");
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open ETH/UCY file");
  static const char* kColumns[] = {"frame_id", "ped_id", "x", "y"};

  std::vector<Row> rows;
  std::string text;
  std::size_t line = 0;
  double last_frame = -INFINITY;
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.find_first_not_of(" \t") == std::string::npos) continue;
    std::istringstream fields(text);
    std::vector<std::string> tok;
    for (std::string t; fields >> t;) tok.push_back(t);
    FS_THROW_UNLESS(tok.size() == 4, path, ":", line,
                    ": expected 4 columns (frame_id ped_id x y), got ", tok.size());
    Row r{};
    r.frame = ParseField(tok[0], path, line, kColumns[0]);
    const double ped = ParseField(tok[1], path, line, kColumns[1]);
    // Ids and frames are integers; beyond 2^53 a double no longer holds every integer (and the
    // conversions below would overflow).
    constexpr double kMaxInteger = 9007199254740992.0;  // 2^53
    FS_THROW_UNLESS(ped == std::floor(ped) && std::abs(ped) <= kMaxInteger, path, ":", line,
                    ": ped_id is not an integer in [-2^53, 2^53]: '", tok[1], "'");
    FS_THROW_UNLESS(r.frame == std::floor(r.frame) && std::abs(r.frame) <= kMaxInteger, path, ":",
                    line, ": frame_id is not an integer in [-2^53, 2^53]: '", tok[0], "'");
    r.ped = static_cast<std::int64_t>(ped);
    r.x = ParseField(tok[2], path, line, kColumns[2]);
    r.y = ParseField(tok[3], path, line, kColumns[3]);
    FS_THROW_UNLESS(r.frame >= last_frame, path, ":", line, ": frames are not sorted (frame ",
                    r.frame, " after ", last_frame, ")");
    last_frame = r.frame;
    rows.push_back(r);
  }
  FS_THROW_UNLESS(!rows.empty(), path, ": no observations");

  // Group by pedestrian, in order of appearance; remember the line for duplicate errors.
  std::map<std::int64_t, std::vector<std::pair<double, Eigen::Vector2d>>> by_ped;
  for (const Row& r : rows) {
    auto& seq = by_ped[r.ped];
    FS_THROW_UNLESS(seq.empty() || seq.back().first != r.frame, path, ": pedestrian ", r.ped,
                    " appears twice in frame ", r.frame);
    seq.push_back({r.frame, Eigen::Vector2d(r.x, r.y)});
  }

  // Frame step: most common positive difference within a pedestrian.
  std::map<long, std::size_t> diffs;
  for (const auto& [ped, seq] : by_ped)
    for (std::size_t i = 1; i < seq.size(); ++i)
      ++diffs[std::lround(seq[i].first - seq[i - 1].first)];
  long step = 0;
  std::size_t best = 0;
  for (const auto& [d, c] : diffs)
    if (c > best) best = c, step = d;
  if (step <= 0) step = 1;

  EthUcyReadStats stats;
  stats.rows = rows.size();
  stats.pedestrians = by_ped.size();
  stats.frame_step = step;
  TrackSet set;
  set.source = path;
  set.seconds_per_step = seconds_per_step;
  for (const auto& [ped, seq] : by_ped) {
    std::size_t begin = 0;
    for (std::size_t i = 1; i <= seq.size(); ++i) {
      const bool cut = i == seq.size() || std::lround(seq[i].first - seq[i - 1].first) != step;
      if (!cut) continue;
      if (i < seq.size()) ++stats.gaps_split;
      Track t;
      t.agent_id = ped;
      t.positions.resize(static_cast<Eigen::Index>(i - begin), 2);
      for (std::size_t k = begin; k < i; ++k) {
        t.time.push_back(seq[k].first / static_cast<double>(step) * seconds_per_step);
        t.positions.row(static_cast<Eigen::Index>(k - begin)) = seq[k].second.transpose();
      }
      set.tracks.push_back(std::move(t));
      begin = i;
    }
  }
  stats.tracks = set.tracks.size();
  log::Info(path, ": ", stats.rows, " rows, ", stats.pedestrians, " pedestrians, frame step ",
            stats.frame_step, " = ", seconds_per_step, " s, ", stats.tracks, " tracks (",
            stats.gaps_split, " split at frame gaps)");
  if (stats_out) *stats_out = stats;
  return set;
}

}  // namespace foresight
