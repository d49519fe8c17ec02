#include "inference/manipulation/metrics.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "core/error.h"

namespace foresight::manipulation {

namespace {

/// Peak speed of a minimum-jerk segment over distance / duration.
constexpr double kMinJerkPeakSpeedFactor = 1.875;

void CheckTimedPath(const TimedPath& path, const char* what) {
  FS_THROW_UNLESS(std::isfinite(path.dt) && path.dt > 0, what, ": dt = ", path.dt,
                  " must be finite and > 0");
  FS_THROW_UNLESS(path.positions.allFinite(), what, ": positions [", path.positions.rows(), " x ",
                  path.positions.cols(), "] contain a non-finite entry");
}

/// Third time derivative of `x` [d x T] at sample i (second-order stencils, see the header),
/// written in differences from sample i so a constant path gives exactly zero.
Eigen::VectorXd Jerk(const Eigen::MatrixXd& x, Eigen::Index i, double dt) {
  const Eigen::Index t = x.cols();
  const double scale = 1.0 / (2.0 * dt * dt * dt);
  if (i >= 2 && i + 2 < t)
    return ((x.col(i + 2) - x.col(i - 2)) - 2.0 * (x.col(i + 1) - x.col(i - 1))) * scale;
  // One-sided: forward from i for the first two samples, backward (sign flipped) for the last two.
  const Eigen::Index step = i < 2 ? 1 : -1;
  const auto d = [&](Eigen::Index k) { return x.col(i + step * k) - x.col(i); };
  return static_cast<double>(step) * (18.0 * d(1) - 24.0 * d(2) + 14.0 * d(3) - 3.0 * d(4)) * scale;
}

/// Speed |dx/dt| at sample i (second-order differences); needs T >= 3.
double Speed(const Eigen::MatrixXd& x, Eigen::Index i, double dt) {
  const Eigen::Index t = x.cols();
  if (i > 0 && i + 1 < t) return (x.col(i + 1) - x.col(i - 1)).norm() / (2.0 * dt);
  const Eigen::Index step = i == 0 ? 1 : -1;
  return (4.0 * (x.col(i + step) - x.col(i)) - (x.col(i + 2 * step) - x.col(i))).norm() /
         (2.0 * dt);
}

std::string JsonNumber(const std::optional<double>& v) {
  if (!v || !std::isfinite(*v)) return "null";
  std::ostringstream os;
  os << std::setprecision(17) << *v;
  return os.str();
}

std::string StatJson(const Stat& s) {
  return "{\"mean\": " + JsonNumber(s.mean) + ", \"std\": " + JsonNumber(s.std) +
         ", \"n\": " + std::to_string(s.n) + "}";
}

std::string StatText(const Stat& s, int digits) {
  if (!s.mean) return "n/a";
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << *s.mean;
  if (s.std) os << " +- " << *s.std;
  return os.str();
}

}  // namespace

double TimedPath::duration() const {
  return positions.cols() < 2 ? 0.0 : static_cast<double>(positions.cols() - 1) * dt;
}

double PathLength(const Eigen::MatrixXd& points) {
  FS_THROW_UNLESS(points.allFinite(), "PathLength: points [", points.rows(), " x ", points.cols(),
                  "] contain a non-finite entry");
  double length = 0;
  for (Eigen::Index i = 1; i < points.cols(); ++i)
    length += (points.col(i) - points.col(i - 1)).norm();
  return length;
}

const char* ToString(LdjStatus status) {
  switch (status) {
    case LdjStatus::kOk:
      return "ok";
    case LdjStatus::kNotEvaluated:
      return "not_evaluated";
    case LdjStatus::kTooFewSamples:
      return "too_few_samples";
    case LdjStatus::kNoMotion:
      return "no_motion";
    case LdjStatus::kNonFinite:
      return "non_finite";
  }
  return "unknown";
}

LdjResult LogDimensionlessJerk(const TimedPath& path) {
  CheckTimedPath(path, "LogDimensionlessJerk");
  const Eigen::MatrixXd& x = path.positions;
  const Eigen::Index t = x.cols();
  LdjResult out;
  if (t < kMinLdjSamples) {
    out.status = LdjStatus::kTooFewSamples;
    return out;
  }
  double v_peak = 0;
  for (Eigen::Index i = 0; i < t; ++i) v_peak = std::max(v_peak, Speed(x, i, path.dt));
  const bool still = ((x.colwise() - x.col(0)).array() == 0).all();
  if (still || !(v_peak > 0)) {
    out.status = LdjStatus::kNoMotion;
    return out;
  }
  // Trapezoid rule over the T samples of |jerk|^2.
  double integral = 0;
  for (Eigen::Index i = 0; i < t; ++i) {
    const double w = (i == 0 || i == t - 1) ? 0.5 : 1.0;
    integral += w * Jerk(x, i, path.dt).squaredNorm();
  }
  integral *= path.dt;
  const double duration = path.duration();
  const double dimensionless = duration * duration * duration / (v_peak * v_peak) * integral;
  const double ldj = -std::log(dimensionless);
  if (!std::isfinite(ldj)) {
    out.status = LdjStatus::kNonFinite;
    return out;
  }
  out.status = LdjStatus::kOk;
  out.value = ldj;
  return out;
}

TimedPath TimeParameterise(const Eigen::MatrixXd& waypoints, const JointVector& max_velocity,
                           double dt) {
  FS_THROW_UNLESS(waypoints.rows() == kDof && waypoints.cols() >= 1,
                  "TimeParameterise: waypoints are [", waypoints.rows(), " x ", waypoints.cols(),
                  "], expected [", kDof, " x K] with K >= 1");
  FS_THROW_UNLESS(waypoints.allFinite(), "TimeParameterise: waypoints contain a non-finite entry");
  FS_THROW_UNLESS(max_velocity.allFinite() && (max_velocity.array() > 0).all(),
                  "TimeParameterise: max_velocity [", max_velocity.transpose(),
                  "] must be finite and > 0");
  FS_THROW_UNLESS(std::isfinite(dt) && dt > 0, "TimeParameterise: dt = ", dt,
                  " must be finite and > 0");
  const Eigen::Index k = waypoints.cols();
  std::vector<Eigen::Index> steps(static_cast<std::size_t>(k > 1 ? k - 1 : 0), 0);
  Eigen::Index total = 1;
  for (Eigen::Index s = 0; s + 1 < k; ++s) {
    const JointVector delta = waypoints.col(s + 1) - waypoints.col(s);
    if (delta.cwiseAbs().maxCoeff() == 0) continue;
    const double duration =
        kMinJerkPeakSpeedFactor * (delta.cwiseAbs().array() / max_velocity.array()).maxCoeff();
    // Round up (with a relative slack so an exact multiple of dt is not pushed one step further).
    const double n = std::ceil(duration / dt * (1.0 - 1e-12));
    FS_THROW_UNLESS(n < 1e8, "TimeParameterise: segment ", s, " needs ", n, " samples at dt = ", dt,
                    " (dt too small or limits too low)");
    steps[static_cast<std::size_t>(s)] = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(n));
    total += steps[static_cast<std::size_t>(s)];
  }
  TimedPath out;
  out.dt = dt;
  out.positions.resize(kDof, total);
  out.positions.col(0) = waypoints.col(0);
  Eigen::Index c = 1;
  for (Eigen::Index s = 0; s + 1 < k; ++s) {
    const Eigen::Index n = steps[static_cast<std::size_t>(s)];
    const JointVector a = waypoints.col(s);
    const JointVector delta = waypoints.col(s + 1) - a;
    for (Eigen::Index i = 1; i <= n; ++i, ++c) {
      const double u = static_cast<double>(i) / static_cast<double>(n);
      const double shape = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
      out.positions.col(c) =
          i == n ? JointVector(waypoints.col(s + 1)) : JointVector(a + delta * shape);
    }
  }
  return out;
}

Eigen::Matrix3Xd EndEffectorPath(const TimedPath& joints, const EndEffectorFn& ee_position) {
  FS_THROW_UNLESS(joints.positions.rows() == kDof, "EndEffectorPath: joints are [",
                  joints.positions.rows(), " x ", joints.positions.cols(), "], expected [", kDof,
                  " x T]");
  FS_THROW_UNLESS(static_cast<bool>(ee_position), "EndEffectorPath: no forward kinematics given");
  Eigen::Matrix3Xd ee(3, joints.positions.cols());
  for (Eigen::Index i = 0; i < joints.positions.cols(); ++i)
    ee.col(i) = ee_position(joints.positions.col(i));
  return ee;
}

PathMetrics PathMetrics::Failure(double generation_time_s) {
  PathMetrics m;
  m.success = false;
  m.time_s = generation_time_s;
  return m;
}

PathMetrics EvaluateJointPath(const TimedPath& joints, double generation_time_s) {
  CheckTimedPath(joints, "EvaluateJointPath");
  FS_THROW_UNLESS(joints.positions.rows() == kDof && joints.positions.cols() >= 1,
                  "EvaluateJointPath: joints are [", joints.positions.rows(), " x ",
                  joints.positions.cols(), "], expected [", kDof, " x T] with T >= 1");
  FS_THROW_UNLESS(std::isfinite(generation_time_s) && generation_time_s >= 0,
                  "EvaluateJointPath: generation time ", generation_time_s,
                  " s must be finite and >= 0");
  PathMetrics m;
  m.success = true;
  m.time_s = generation_time_s;
  m.cspace_length = PathLength(joints.positions);
  m.duration_s = joints.duration();
  m.cspace_ldj = LogDimensionlessJerk(joints);
  return m;
}

PathMetrics EvaluatePath(const TimedPath& joints, const Eigen::Matrix3Xd& ee_positions,
                         double generation_time_s) {
  PathMetrics m = EvaluateJointPath(joints, generation_time_s);
  FS_THROW_UNLESS(ee_positions.cols() == joints.positions.cols(),
                  "EvaluatePath: ", ee_positions.cols(), " EE positions for ",
                  joints.positions.cols(), " joint samples");
  const TimedPath ee{ee_positions, joints.dt};
  CheckTimedPath(ee, "EvaluatePath (EE positions)");
  m.ee_length = PathLength(ee.positions);
  m.ee_ldj = LogDimensionlessJerk(ee);
  return m;
}

PathMetrics EvaluatePathWithKinematics(const TimedPath& joints, const EndEffectorFn& ee_position,
                                       double generation_time_s) {
  return EvaluatePath(joints, EndEffectorPath(joints, ee_position), generation_time_s);
}

Stat ComputeStat(const std::vector<double>& values) {
  Stat s;
  s.n = static_cast<int>(values.size());
  if (values.empty()) return s;
  double sum = 0;
  for (double v : values) {
    FS_THROW_UNLESS(std::isfinite(v), "ComputeStat: non-finite value ", v);
    sum += v;
  }
  const double mean = sum / static_cast<double>(values.size());
  s.mean = mean;
  if (values.size() >= 2) {
    double ss = 0;
    for (double v : values) ss += (v - mean) * (v - mean);
    s.std = std::sqrt(ss / static_cast<double>(values.size() - 1));
  }
  return s;
}

MetricSummary Summarise(const std::vector<PathMetrics>& attempts) {
  MetricSummary out;
  out.problems = static_cast<int>(attempts.size());
  std::vector<double> ee_length, cspace_length, time_s, duration_s, ee_ldj, cspace_ldj;
  for (const PathMetrics& m : attempts) {
    if (!m.success) continue;
    ++out.successes;
    time_s.push_back(m.time_s);
    if (m.ee_length) ee_length.push_back(*m.ee_length);
    if (m.cspace_length) cspace_length.push_back(*m.cspace_length);
    if (m.duration_s) duration_s.push_back(*m.duration_s);
    if (m.ee_ldj.ok()) ee_ldj.push_back(*m.ee_ldj.value);
    if (m.cspace_ldj.ok()) cspace_ldj.push_back(*m.cspace_ldj.value);
  }
  out.success_rate =
      out.problems > 0 ? static_cast<double>(out.successes) / static_cast<double>(out.problems) : 0;
  out.ee_length = ComputeStat(ee_length);
  out.cspace_length = ComputeStat(cspace_length);
  out.time_s = ComputeStat(time_s);
  out.duration_s = ComputeStat(duration_s);
  out.ee_ldj = ComputeStat(ee_ldj);
  out.cspace_ldj = ComputeStat(cspace_ldj);
  return out;
}

std::string MetricSummary::BriefReport() const {
  std::ostringstream os;
  os << successes << "/" << problems << " solved (" << std::fixed << std::setprecision(1)
     << 100.0 * success_rate << "%), EE length " << StatText(ee_length, 2) << " m, C-space length "
     << StatText(cspace_length, 2) << " rad, time " << StatText(time_s, 3) << " s, EE-LDJ "
     << StatText(ee_ldj, 2) << ", C-space LDJ " << StatText(cspace_ldj, 2);
  return os.str();
}

std::string MetricSummary::ToJson() const {
  std::ostringstream os;
  os << "{\"problems\": " << problems << ", \"successes\": " << successes
     << ", \"success_rate\": " << JsonNumber(success_rate)
     << ", \"ee_length\": " << StatJson(ee_length)
     << ", \"cspace_length\": " << StatJson(cspace_length) << ", \"time_s\": " << StatJson(time_s)
     << ", \"duration_s\": " << StatJson(duration_s) << ", \"ee_ldj\": " << StatJson(ee_ldj)
     << ", \"cspace_ldj\": " << StatJson(cspace_ldj) << "}\n";
  return os.str();
}

}  // namespace foresight::manipulation
