#pragma once
/// Reader of CARMEN text logs (old-style FLASER front-laser messages), e.g. the GMapping-corrected
/// Intel Research Lab log; see ../shared/data/intel_lab/README.md.
///
/// A FLASER line is
///   FLASER n r_0 ... r_{n-1} x y theta odom_x odom_y odom_theta ipc_timestamp hostname
///   logger_timestamp
/// with ranges in metres and the corrected laser pose X_WL = (x, y, theta) right after the ranges.
/// The n beams cover 180 degrees: beam i is at world angle theta - pi/2 + i * pi / n
/// (angle_min = -pi/2, angle_increment = pi/n; for n = 180 the beams are 1 degree apart).
/// The scan time is ipc_timestamp (s). Other messages (ODOM, NEFF, PARAM, ...), blank lines and
/// `#` comment lines are ignored.

#include <string>
#include <vector>

#include "datasets/laser_scan.h"

namespace foresight {

struct CarmenReadOptions {
  /// Every FLASER message must have the beam count of the first one (else an Error).
  bool require_constant_beam_count = true;
};

/// Reads every FLASER message of the log at `path`, in file order (robot 0).
/// Errors (foresight::Error naming file and line): missing file, no FLASER message, a line with
/// the wrong number of fields for its beam count, a non-numeric field, a beam count that is not a
/// positive integer or differs from the first (when required), a non-finite pose or timestamp.
/// Range readings are kept as written, even NaN, negative or "no return" (>= max range) values:
/// SampleLabelledPoints() drops and counts such beams.
std::vector<LaserScan> ReadCarmenLog(const std::string& path,
                                     const CarmenReadOptions& options = {});

}  // namespace foresight
