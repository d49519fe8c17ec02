#pragma once
/// Labelled occupancy points from laser scans, the training and test data of Hilbert-map style
/// occupancy classifiers: the end point of every valid beam is a hit (occupied = 1) and points
/// sampled uniformly along the beam before it are free (occupied = 0). See
/// ../shared/data/intel_lab/README.md ("Turning it into classifier data"); with the defaults
/// (0.5 free points per metre, at least one per beam, 40 m cut-off) each kept beam of range d gives
/// 1 + max(1, floor(d / 2)) points, as in the Hilbert-maps reference code.
///
/// Also the scan-level splits of the thesis Fast-BHM experiments (chapter 3): every k-th scan held
/// out for testing, and the four-quadrant split of the training scans for map fusion.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "core/config.h"
#include "datasets/laser_scan.h"

namespace foresight {

struct OccupancyPointsConfig {
  /// Beams with range >= max_range (m), <= 0 or non-finite are dropped (and counted).
  double max_range = 40.0;
  double free_per_metre = 0.5;  ///< free points per metre of beam
  int min_free_per_beam = 1;    ///< at least this many free points per kept beam
  /// Free points are uniform on [0, range - free_end_margin] (m), clamped at 0.
  double free_end_margin = 0.1;

  template <class A>
  void Serialize(A* a) {
    a->Visit("max_range", &max_range, config::Range::Positive(),
             "beams with range >= max_range (m), <= 0 or non-finite are dropped entirely");
    a->Visit("free_per_metre", &free_per_metre, config::Range::NonNegative(),
             "free points per metre of beam: floor(range * free_per_metre) per beam");
    a->Visit("min_free_per_beam", &min_free_per_beam, config::Range::AtLeast(0),
             "at least this many free points per kept beam");
    a->Visit("free_end_margin", &free_end_margin, config::Range::NonNegative(),
             "free points are uniform on [0, range - free_end_margin] along the beam (m)");
  }
};

/// Labelled points of a set of scans, grouped by scan (CSR layout).
struct LabelledPoints {
  Eigen::Matrix2Xd xy;                 ///< [2 x size()] world coordinates p_WQ (m)
  std::vector<std::uint8_t> occupied;  ///< [size()] 1 = beam end point (hit), 0 = free sample
  /// [scans + 1] the points of scan s are [scan_begin[s], scan_begin[s + 1]).
  std::vector<std::int64_t> scan_begin{0};
  std::vector<int> robot;          ///< [scans] recording robot of each scan
  std::int64_t dropped_beams = 0;  ///< beams rejected when sampling (no return / invalid)

  std::int64_t size() const { return static_cast<std::int64_t>(xy.cols()); }
  int num_scans() const { return static_cast<int>(robot.size()); }
  /// Number of points of scan `s`.
  std::int64_t ScanSize(int s) const { return scan_begin[s + 1] - scan_begin[s]; }
  /// Number of hit points (occupied == 1).
  std::int64_t NumOccupied() const;
};

/// Samples labelled points of every scan; within a scan, each kept beam contributes its hit
/// followed by n_free = max(min_free_per_beam, floor(range * free_per_metre)) free points at
/// distances uniform on [0, max(0, range - free_end_margin)] from the laser.
/// Deterministic in (scans, config, seed): scan s draws from its own generator seeded by
/// (seed, s), so the points of a scan do not depend on the other scans (sampling a prefix of a log
/// gives the same points for those scans). Errors: config out of range, a non-finite scan pose.
LabelledPoints SampleLabelledPoints(const std::vector<LaserScan>& scans,
                                    const OccupancyPointsConfig& config, std::uint64_t seed);

/// Scan-level split: scan i is held out for testing when i % test_every == test_offset
/// (the thesis's 9:1 split with test_every = 10). Requires test_every >= 1 and
/// 0 <= test_offset < test_every.
struct ScanSplit {
  std::vector<int> train, test;
};
ScanSplit SplitEveryKth(int num_scans, int test_every, int test_offset);

/// Points of the listed scans, in the listed order (scan ids of the result are 0..k-1, robot
/// kept). dropped_beams of the result is 0: beams are counted when sampling, not per scan.
LabelledPoints SelectScans(const LabelledPoints& points, const std::vector<int>& scans);

/// The thesis fusion split (chapter 3, "Fusion of Fast-BHM"): each of the candidate `scans` goes to
/// the quadrant of the mean of its hit points relative to the centre (cx, cy):
/// 0 upper-left (x < cx, y >= cy), 1 upper-right (x >= cx, y >= cy), 2 lower-left (x < cx, y < cy),
/// 3 lower-right (x >= cx, y < cy). Returns per-quadrant lists of scan indices (into `points`'
/// scans) in candidate order. Scans without any hit carry no points and are in no quadrant.
std::array<std::vector<int>, 4> QuadrantSplit(const LabelledPoints& points,
                                              const std::vector<int>& scans, double cx, double cy);

}  // namespace foresight
