#include "datasets/carmen.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"

namespace foresight {
namespace {

// Fields after the ranges: x y theta odom_x odom_y odom_theta ipc_timestamp hostname
// logger_timestamp.
constexpr long long kFieldsAfterRanges = 9;
constexpr long long kMaxBeams = 1'000'000;

class LineContext {
 public:
  LineContext(const std::string& path, std::size_t line) : path_(path), line_(line) {}

  /// The number in field `index` (0-based over the whole line), named `what` in errors.
  double Number(const std::vector<std::string>& fields, std::size_t index,
                const std::string& what) const {
    const std::optional<double> v = ParseDouble(fields[index]);
    FS_THROW_UNLESS(v.has_value(), path_, ":", line_, ": FLASER field ", index + 1, " (", what,
                    ") is not a number: '", fields[index], "'");
    return *v;
  }
  double Finite(const std::vector<std::string>& fields, std::size_t index,
                const std::string& what) const {
    const double v = Number(fields, index, what);
    FS_THROW_UNLESS(std::isfinite(v), path_, ":", line_, ": FLASER field ", index + 1, " (", what,
                    ") is not finite: '", fields[index], "'");
    return v;
  }

 private:
  const std::string& path_;
  std::size_t line_;
};

}  // namespace

std::vector<LaserScan> ReadCarmenLog(const std::string& path, const CarmenReadOptions& options) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open CARMEN log");

  std::vector<LaserScan> scans;
  std::size_t first_line = 0, line = 0, other_messages = 0;
  std::string text;
  while (std::getline(in, text)) {
    ++line;
    std::istringstream stream(text);
    std::vector<std::string> fields;
    for (std::string f; stream >> f;) fields.push_back(f);
    if (fields.empty() || fields[0][0] == '#') continue;
    if (fields[0] != "FLASER") {
      ++other_messages;
      continue;
    }
    FS_THROW_UNLESS(fields.size() >= 2, path, ":", line, ": FLASER message without a beam count");
    const std::optional<long long> n = ParseInteger(fields[1]);
    FS_THROW_UNLESS(n.has_value() && *n > 0, path, ":", line,
                    ": FLASER beam count is not a positive integer: '", fields[1], "'");
    FS_THROW_UNLESS(*n <= kMaxBeams, path, ":", line, ": FLASER beam count ", *n,
                    " is implausible (more than ", kMaxBeams, ")");
    const long long expected = 2 + *n + kFieldsAfterRanges;
    FS_THROW_UNLESS(static_cast<long long>(fields.size()) == expected, path, ":", line,
                    ": FLASER with ", *n, " beams needs ", expected,
                    " fields (FLASER n, n ranges, x y theta odom_x odom_y odom_theta "
                    "ipc_timestamp hostname logger_timestamp), got ",
                    fields.size());
    if (options.require_constant_beam_count && !scans.empty()) {
      FS_THROW_UNLESS(static_cast<long long>(scans.front().ranges.size()) == *n, path, ":", line,
                      ": FLASER has ", *n, " beams but the first scan (line ", first_line, ") has ",
                      scans.front().ranges.size());
    }
    if (scans.empty()) first_line = line;

    const LineContext at(path, line);
    const std::size_t beams = static_cast<std::size_t>(*n);
    LaserScan scan;
    scan.ranges.resize(beams);
    for (std::size_t i = 0; i < beams; ++i)
      scan.ranges[i] = at.Number(fields, 2 + i, "range " + std::to_string(i));
    const std::size_t p = 2 + beams;
    scan.x = at.Finite(fields, p + 0, "x");
    scan.y = at.Finite(fields, p + 1, "y");
    scan.theta = at.Finite(fields, p + 2, "theta");
    at.Number(fields, p + 3, "odom_x");
    at.Number(fields, p + 4, "odom_y");
    at.Number(fields, p + 5, "odom_theta");
    scan.time = at.Finite(fields, p + 6, "ipc_timestamp");
    at.Number(fields, p + 8, "logger_timestamp");
    scan.robot = 0;
    scan.angle_min = -M_PI / 2;
    scan.angle_increment = M_PI / static_cast<double>(beams);
    scans.push_back(std::move(scan));
  }
  FS_THROW_UNLESS(!scans.empty(), path, ": no FLASER messages in ", line, " lines");
  log::Info(path, ": ", scans.size(), " FLASER scans of ", scans.front().ranges.size(), " beams (",
            other_messages, " other messages ignored)");
  return scans;
}

}  // namespace foresight
