#include "datasets/occ_traj.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <string_view>

#include "core/error.h"

namespace foresight::otnet {
namespace {

namespace fs = std::filesystem;

/// Whitespace-separated tokens of `line` (views into it).
void SplitWhitespace(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t begin = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > begin) tokens->push_back(line.substr(begin, i - begin));
  }
}

bool IsBlank(std::string_view line) {
  return std::all_of(line.begin(), line.end(),
                     [](char ch) { return std::isspace(static_cast<unsigned char>(ch)) != 0; });
}

/// getline without the '\r' of CRLF files.
bool GetLine(std::istream& in, std::string* line) {
  if (!std::getline(in, *line)) return false;
  if (!line->empty() && line->back() == '\r') line->pop_back();
  return true;
}

/// `line` without leading and trailing whitespace.
std::string_view Trim(std::string_view line) {
  std::size_t b = 0, e = line.size();
  while (b < e && std::isspace(static_cast<unsigned char>(line[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(line[e - 1]))) --e;
  return line.substr(b, e - b);
}

/// `traj-<k>:` with k a non-negative integer (surrounding whitespace allowed).
bool IsTrajectoryHeader(std::string_view line) {
  const std::string_view t = Trim(line);
  constexpr std::string_view kPrefix = "traj-";
  if (t.size() < kPrefix.size() + 2 || t.substr(0, kPrefix.size()) != kPrefix || t.back() != ':')
    return false;
  const std::string_view k = t.substr(kPrefix.size(), t.size() - kPrefix.size() - 1);
  return std::all_of(k.begin(), k.end(),
                     [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)) != 0; });
}

/// The numbers of one coordinate line; Error naming file, line, column and token otherwise.
void ParseCoordinates(std::string_view line, const std::string& path, int line_no, const char* axis,
                      std::vector<std::string_view>* tokens, std::vector<double>* values) {
  SplitWhitespace(line, tokens);
  values->clear();
  for (std::size_t i = 0; i < tokens->size(); ++i) {
    const std::string_view t = (*tokens)[i];
    double v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    FS_THROW_UNLESS(ec == std::errc() && end == t.data() + t.size(), path, ":", line_no, ": ", axis,
                    " value ", i + 1, " is not a number: '", t, "'");
    FS_THROW_UNLESS(std::isfinite(v), path, ":", line_no, ": ", axis, " value ", i + 1,
                    " is not finite: '", t, "'");
    values->push_back(v);
  }
}

}  // namespace

void ReadReport::Add(const ReadReport& o) {
  trajectories += o.trajectories;
  kept += o.kept;
  dropped_outside += o.dropped_outside;
  dropped_occupied += o.dropped_occupied;
  dropped_too_short += o.dropped_too_short;
}

BinaryGrid ReadOccTrajMap(const std::string& path, int expected_width, int expected_height) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open Occ-Traj120 map file");
  std::vector<std::uint8_t> cells;
  int width = -1, height = 0, line_no = 0, first_row_line = 0;
  std::string line;
  std::vector<std::string_view> tokens;
  while (GetLine(in, &line)) {
    ++line_no;
    // numpy prints "[[1 0 ...]\n [0 1 ...]]": brackets only delimit rows, one row per line.
    std::replace_if(
        line.begin(), line.end(), [](char ch) { return ch == '[' || ch == ']'; }, ' ');
    SplitWhitespace(line, &tokens);
    if (tokens.empty()) continue;
    if (width < 0) {
      width = static_cast<int>(tokens.size());
      first_row_line = line_no;
      FS_THROW_UNLESS(expected_width <= 0 || width == expected_width, path, ":", line_no,
                      ": the first map row has ", width, " entries, expected width ",
                      expected_width);
    }
    FS_THROW_UNLESS(static_cast<int>(tokens.size()) == width, path, ":", line_no,
                    ": ragged map row with ", tokens.size(), " entries, expected ", width,
                    " (as in the first row, line ", first_row_line, ")");
    for (std::size_t c = 0; c < tokens.size(); ++c) {
      FS_THROW_UNLESS(tokens[c] == "0" || tokens[c] == "1", path, ":", line_no, ": map entry ",
                      c + 1, " is '", tokens[c], "', expected 0 or 1");
      cells.push_back(tokens[c] == "1" ? 1 : 0);
    }
    ++height;
  }
  FS_THROW_UNLESS(!in.bad(), path, ": read error after line ", line_no);
  FS_THROW_UNLESS(height > 0, path, ":", std::max(line_no, 1),
                  ": no map rows (empty file or only brackets/blank lines)");
  FS_THROW_UNLESS(expected_height <= 0 || height == expected_height, path, ":", line_no,
                  ": the map has ", height, " rows, expected height ", expected_height);
  BinaryGrid grid(width, height);
  grid.cells = std::move(cells);
  return grid;
}

std::vector<Eigen::MatrixX2d> ReadOccTrajTrajectories(const std::string& path,
                                                      const BinaryGrid& map,
                                                      BadWaypointPolicy policy,
                                                      ReadReport* report) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open Occ-Traj120 trajectory file");
  ReadReport counts;
  std::vector<Eigen::MatrixX2d> out;
  std::string header, xline, yline;
  std::vector<std::string_view> tokens;
  std::vector<double> xs, ys;
  int line_no = 0;
  while (GetLine(in, &header)) {
    ++line_no;
    if (IsBlank(header)) continue;  // blank lines between blocks are harmless
    const int header_line = line_no;
    FS_THROW_UNLESS(IsTrajectoryHeader(header), path, ":", line_no,
                    ": expected a block header 'traj-<k>:', found '", header, "'");
    // A block is exactly three lines; a header (or the end of the file) in place of a
    // coordinate line means the block was cut short.
    const auto read_coordinate_line = [&](std::string* text, const char* axis) {
      const bool got = GetLine(in, text);
      if (got) ++line_no;
      FS_THROW_UNLESS(got && !IsTrajectoryHeader(*text), path, ":", line_no, ": truncated block ",
                      header, " (line ", header_line, ") has no ", axis, " line",
                      got ? internal::Concat(", found '", *text, "'") : " before the end");
    };
    read_coordinate_line(&xline, "x");
    const int x_line = line_no;
    ParseCoordinates(xline, path, x_line, "x", &tokens, &xs);
    read_coordinate_line(&yline, "y");
    const int y_line = line_no;
    ParseCoordinates(yline, path, y_line, "y", &tokens, &ys);
    FS_THROW_UNLESS(xs.size() == ys.size(), path, ":", y_line, ": ", header, " has ", xs.size(),
                    " x values (line ", x_line, ") but ", ys.size(), " y values");
    ++counts.trajectories;

    if (xs.size() < 2) {
      FS_THROW_UNLESS(policy == BadWaypointPolicy::kDrop, path, ":", x_line, ": ", header, " has ",
                      xs.size(), " waypoint(s), fewer than 2");
      ++counts.dropped_too_short;
      continue;
    }
    // Outside the map is checked over the whole trajectory before occupancy, so each dropped
    // trajectory is counted once, under its most basic fault.
    bool outside = false, occupied = false;
    std::size_t bad = 0;
    for (std::size_t i = 0; i < xs.size() && !outside; ++i) {
      if (!(xs[i] >= 0 && ys[i] >= 0 && xs[i] < map.width && ys[i] < map.height)) {
        outside = true;
        bad = i;
      } else if (!occupied && map.OccupiedAt(xs[i], ys[i])) {
        occupied = true;
        bad = i;
      }
    }
    if (outside || occupied) {
      FS_THROW_UNLESS(
          policy == BadWaypointPolicy::kDrop, path, ":", x_line, ": ", header, " waypoint ",
          bad + 1, " (x=", xs[bad], ", y=", ys[bad], ") is ",
          outside
              ? internal::Concat("outside the ", map.width, " x ", map.height, " map")
              : internal::Concat("in an occupied cell (row ", static_cast<int>(std::floor(ys[bad])),
                                 ", column ", static_cast<int>(std::floor(xs[bad])), ")"));
      ++(outside ? counts.dropped_outside : counts.dropped_occupied);
      continue;
    }
    Eigen::MatrixX2d t(static_cast<Eigen::Index>(xs.size()), 2);
    for (std::size_t i = 0; i < xs.size(); ++i) {
      t(static_cast<Eigen::Index>(i), 0) = xs[i];
      t(static_cast<Eigen::Index>(i), 1) = ys[i];
    }
    out.push_back(std::move(t));
    ++counts.kept;
  }
  FS_THROW_UNLESS(!in.bad(), path, ": read error after line ", line_no);
  if (report != nullptr) *report = counts;
  return out;
}

std::vector<std::string> ListOccTrajMaps(const std::string& root) {
  const std::string path = (fs::path(root) / "train_maps.txt").string();
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open the Occ-Traj120 map list (root '", root, "')");
  std::vector<std::string> ids;
  std::set<std::string> seen;
  std::string line;
  std::vector<std::string_view> tokens;
  int line_no = 0;
  while (GetLine(in, &line)) {
    ++line_no;
    SplitWhitespace(line, &tokens);
    if (tokens.empty()) continue;
    FS_THROW_UNLESS(tokens.size() == 1, path, ":", line_no, ": expected one map id, found '", line,
                    "'");
    std::string id(tokens[0]);
    FS_THROW_UNLESS(id.find('/') == std::string::npos && id != "." && id != "..", path, ":",
                    line_no, ": map id '", id, "' is not a file-name part");
    FS_THROW_UNLESS(seen.insert(id).second, path, ":", line_no, ": duplicate map id '", id, "'");
    ids.push_back(std::move(id));
  }
  FS_THROW_UNLESS(!in.bad(), path, ": read error after line ", line_no);
  FS_THROW_UNLESS(!ids.empty(), path, ": no map ids (empty list)");
  return ids;
}

MapTrajectories LoadOccTrajMap(const std::string& root, const std::string& id, int map_size,
                               BadWaypointPolicy policy, ReadReport* report) {
  FS_THROW_UNLESS(map_size > 0, "LoadOccTrajMap: map_size must be positive, got ", map_size,
                  " (map '", id, "')");
  const fs::path base(root);
  MapTrajectories m;
  m.id = id;
  m.map =
      ReadOccTrajMap((base / "maps" / ("occtraj_" + id + "_map.txt")).string(), map_size, map_size);
  m.trajectories = ReadOccTrajTrajectories(
      (base / "trajs" / ("occtraj_" + id + "_trajs.txt")).string(), m.map, policy, report);
  return m;
}

MapSplit SplitMaps(std::vector<std::string> ids, double val_fraction, double test_fraction,
                   std::uint64_t seed) {
  FS_THROW_UNLESS(val_fraction >= 0 && val_fraction < 1, "SplitMaps: val_fraction ", val_fraction,
                  " is outside [0, 1)");
  FS_THROW_UNLESS(test_fraction >= 0 && test_fraction < 1, "SplitMaps: test_fraction ",
                  test_fraction, " is outside [0, 1)");
  FS_THROW_UNLESS(val_fraction + test_fraction < 1, "SplitMaps: val_fraction ", val_fraction,
                  " + test_fraction ", test_fraction, " must be < 1");
  std::sort(ids.begin(), ids.end());
  const auto dup = std::adjacent_find(ids.begin(), ids.end());
  FS_THROW_UNLESS(dup == ids.end(), "SplitMaps: duplicate map id '",
                  dup == ids.end() ? std::string() : *dup, "'");
  const std::size_t n = ids.size();
  const auto n_test = static_cast<std::size_t>(std::round(test_fraction * n));
  const auto n_val = static_cast<std::size_t>(std::round(val_fraction * n));
  FS_THROW_UNLESS(n_test >= 1 && n_val >= 1 && n_test + n_val < n, "SplitMaps: ", n,
                  " maps with val_fraction ", val_fraction, " and test_fraction ", test_fraction,
                  " give ", n - std::min(n, n_test + n_val), " train, ", n_val, " val and ", n_test,
                  " test maps; every part must be non-empty");

  // Fisher-Yates with our own bounded draw: std::shuffle and std::uniform_int_distribution are
  // implementation-defined, std::mt19937_64's output sequence is not.
  std::mt19937_64 rng(seed);
  for (std::size_t i = n - 1; i > 0; --i) {
    const std::uint64_t range = static_cast<std::uint64_t>(i) + 1;
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() -
                                std::numeric_limits<std::uint64_t>::max() % range;
    std::uint64_t r = rng();
    while (r >= limit) r = rng();
    std::swap(ids[i], ids[static_cast<std::size_t>(r % range)]);
  }
  MapSplit split;
  split.test.assign(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(n_test));
  split.val.assign(ids.begin() + static_cast<std::ptrdiff_t>(n_test),
                   ids.begin() + static_cast<std::ptrdiff_t>(n_test + n_val));
  split.train.assign(ids.begin() + static_cast<std::ptrdiff_t>(n_test + n_val), ids.end());
  std::sort(split.train.begin(), split.train.end());
  std::sort(split.val.begin(), split.val.end());
  std::sort(split.test.begin(), split.test.end());
  return split;
}

}  // namespace foresight::otnet
