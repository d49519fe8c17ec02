#include "datasets/occupancy_points.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "core/portable_random.h"

namespace foresight {
namespace {

bool KeepBeam(double range, double max_range) {
  return std::isfinite(range) && range > 0 && range < max_range;
}

std::int64_t FreeCount(double range, const OccupancyPointsConfig& c) {
  const double n = std::floor(range * c.free_per_metre);
  FS_THROW_UNLESS(n < 1e9, "occupancy points: a beam of ", range, " m at free_per_metre ",
                  c.free_per_metre, " asks for ", n, " free points");
  return std::max<std::int64_t>(c.min_free_per_beam, static_cast<std::int64_t>(n));
}

/// A generator of its own for scan `scan`: the points of a scan do not depend on other scans.
std::mt19937_64 ScanGenerator(std::uint64_t seed, std::size_t scan) {
  const std::uint64_t s = scan;
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(s), static_cast<std::uint32_t>(s >> 32)};
  return std::mt19937_64(seq);
}

void CheckScanIndex(const LabelledPoints& points, int s, const char* where) {
  FS_THROW_UNLESS(s >= 0 && s < points.num_scans(), where, ": scan index ", s,
                  " is out of range [0, ", points.num_scans(), ")");
}

}  // namespace

std::int64_t LabelledPoints::NumOccupied() const {
  return std::count(occupied.begin(), occupied.end(), std::uint8_t{1});
}

LabelledPoints SampleLabelledPoints(const std::vector<LaserScan>& scans,
                                    const OccupancyPointsConfig& c, std::uint64_t seed) {
  FS_THROW_UNLESS(c.max_range > 0, "occupancy points: max_range must be > 0, got ", c.max_range);
  FS_THROW_UNLESS(c.free_per_metre >= 0 && std::isfinite(c.free_per_metre),
                  "occupancy points: free_per_metre must be finite and >= 0, got ",
                  c.free_per_metre);
  FS_THROW_UNLESS(c.min_free_per_beam >= 0,
                  "occupancy points: min_free_per_beam must be >= 0, got ", c.min_free_per_beam);
  FS_THROW_UNLESS(c.free_end_margin >= 0, "occupancy points: free_end_margin must be >= 0, got ",
                  c.free_end_margin);

  // Pass 1: sizes (independent of the generator).
  LabelledPoints out;
  out.scan_begin.assign(1, 0);
  out.scan_begin.reserve(scans.size() + 1);
  out.robot.reserve(scans.size());
  std::int64_t total = 0;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    const LaserScan& scan = scans[s];
    FS_THROW_UNLESS(std::isfinite(scan.x) && std::isfinite(scan.y) && std::isfinite(scan.theta),
                    "occupancy points: scan ", s, " (t = ", scan.time, ") has a non-finite pose (",
                    scan.x, ", ", scan.y, ", ", scan.theta, ")");
    for (double r : scan.ranges) {
      if (KeepBeam(r, c.max_range))
        total += 1 + FreeCount(r, c);
      else
        ++out.dropped_beams;
    }
    out.scan_begin.push_back(total);
    out.robot.push_back(scan.robot);
  }

  // Pass 2: points. Per kept beam: the hit, then its free samples.
  out.xy.resize(2, total);
  out.occupied.resize(static_cast<std::size_t>(total));
  std::int64_t k = 0;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    const LaserScan& scan = scans[s];
    std::mt19937_64 rng = ScanGenerator(seed, s);
    for (int i = 0; i < scan.num_beams(); ++i) {
      const double r = scan.ranges[i];
      if (!KeepBeam(r, c.max_range)) continue;
      const double angle = scan.BeamAngle(i);
      const Eigen::Vector2d p_WL(scan.x, scan.y);
      const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
      out.xy.col(k) = p_WL + r * dir;
      out.occupied[k++] = 1;
      const double free_end = std::max(0.0, r - c.free_end_margin);
      for (std::int64_t j = FreeCount(r, c); j > 0; --j) {
        out.xy.col(k) = p_WL + (free_end * Uniform01(&rng)) * dir;
        out.occupied[k++] = 0;
      }
    }
  }
  return out;
}

ScanSplit SplitEveryKth(int num_scans, int test_every, int test_offset) {
  FS_THROW_UNLESS(num_scans >= 0, "SplitEveryKth: num_scans must be >= 0, got ", num_scans);
  FS_THROW_UNLESS(test_every >= 1, "SplitEveryKth: test_every must be >= 1, got ", test_every);
  FS_THROW_UNLESS(test_offset >= 0 && test_offset < test_every, "SplitEveryKth: test_offset ",
                  test_offset, " is not in [0, test_every = ", test_every, ")");
  ScanSplit split;
  for (int i = 0; i < num_scans; ++i)
    (i % test_every == test_offset ? split.test : split.train).push_back(i);
  return split;
}

LabelledPoints SelectScans(const LabelledPoints& points, const std::vector<int>& scans) {
  std::int64_t total = 0;
  for (int s : scans) {
    CheckScanIndex(points, s, "SelectScans");
    total += points.ScanSize(s);
  }
  LabelledPoints out;
  out.xy.resize(2, total);
  out.occupied.reserve(static_cast<std::size_t>(total));
  out.scan_begin.reserve(scans.size() + 1);
  out.robot.reserve(scans.size());
  std::int64_t k = 0;
  for (int s : scans) {
    const std::int64_t begin = points.scan_begin[s], n = points.ScanSize(s);
    out.xy.middleCols(k, n) = points.xy.middleCols(begin, n);
    out.occupied.insert(out.occupied.end(), points.occupied.begin() + begin,
                        points.occupied.begin() + begin + n);
    k += n;
    out.scan_begin.push_back(k);
    out.robot.push_back(points.robot[s]);
  }
  return out;
}

std::array<std::vector<int>, 4> QuadrantSplit(const LabelledPoints& points,
                                              const std::vector<int>& scans, double cx, double cy) {
  std::array<std::vector<int>, 4> quadrants;
  for (int s : scans) {
    CheckScanIndex(points, s, "QuadrantSplit");
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    std::int64_t hits = 0;
    for (std::int64_t k = points.scan_begin[s]; k < points.scan_begin[s + 1]; ++k) {
      if (!points.occupied[k]) continue;
      sum += points.xy.col(k);
      ++hits;
    }
    if (hits == 0) continue;
    const Eigen::Vector2d mean = sum / static_cast<double>(hits);
    const int column = mean.x() < cx ? 0 : 1;
    const int row = mean.y() >= cy ? 0 : 1;
    quadrants[2 * row + column].push_back(s);
  }
  return quadrants;
}

}  // namespace foresight
