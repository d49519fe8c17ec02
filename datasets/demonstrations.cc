#include "datasets/demonstrations.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/error.h"

namespace foresight {
namespace {

enum class Velocity { kRequired, kOptional, kIgnored };

/// The first non-finite entry of `m` as "(row, col)", or "" when all are finite.
std::string FirstNonFinite(const Eigen::MatrixXd& m) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      if (!std::isfinite(m(r, c))) return internal::Concat("(", r, ", ", c, ") = ", m(r, c));
  return "";
}

/// Everything CheckDemonstrations checks except the goal spread. `where` names the caller.
void CheckStructure(const DemoSet& set, const char* where, Velocity velocity) {
  const std::string& name = set.name;
  FS_THROW_UNLESS(!set.demos.empty(), where, ": demo set '", name, "' has no demonstrations");
  FS_THROW_UNLESS(set.dimension >= 1, where, ": demo set '", name, "' has dimension ",
                  set.dimension, " (expected >= 1)");
  const Eigen::Index d = set.dimension;
  for (std::size_t i = 0; i < set.demos.size(); ++i) {
    const Demonstration& demo = set.demos[i];
    const Eigen::Index n = demo.position.cols();
    FS_THROW_UNLESS(demo.position.rows() == d, where, ": demo set '", name, "' demo ", i,
                    ": position has ", demo.position.rows(), " rows, expected the set's dimension ",
                    d);
    FS_THROW_UNLESS(n >= 3, where, ": demo set '", name, "' demo ", i, ": ", n,
                    " points (at least 3 needed)");
    FS_THROW_UNLESS(demo.time.size() == n, where, ": demo set '", name, "' demo ", i, ": ",
                    demo.time.size(), " time stamps for ", n, " positions");
    const bool has_velocity = demo.velocity.size() > 0;
    if (velocity == Velocity::kRequired)
      FS_THROW_UNLESS(has_velocity, where, ": demo set '", name, "' demo ", i,
                      ": no velocities (fill them with FiniteDifferenceVelocities)");
    if (velocity != Velocity::kIgnored && has_velocity) {
      FS_THROW_UNLESS(demo.velocity.rows() == d && demo.velocity.cols() == n, where, ": demo set '",
                      name, "' demo ", i, ": velocity is [", demo.velocity.rows(), " x ",
                      demo.velocity.cols(), "], position is [", d, " x ", n, "]");
      const std::string bad = FirstNonFinite(demo.velocity);
      FS_THROW_UNLESS(bad.empty(), where, ": demo set '", name, "' demo ", i,
                      ": non-finite velocity ", bad);
    }
    const std::string bad = FirstNonFinite(demo.position);
    FS_THROW_UNLESS(bad.empty(), where, ": demo set '", name, "' demo ", i,
                    ": non-finite position ", bad);
    for (Eigen::Index j = 0; j < n; ++j) {
      FS_THROW_UNLESS(std::isfinite(demo.time(j)), where, ": demo set '", name, "' demo ", i,
                      ": non-finite time ", demo.time(j), " at sample ", j);
      if (j > 0)
        FS_THROW_UNLESS(demo.time(j) > demo.time(j - 1), where, ": demo set '", name, "' demo ", i,
                        ": time does not increase at sample ", j, " (", demo.time(j - 1), " then ",
                        demo.time(j), ")");
    }
  }
}

/// Mean of the final points.
Eigen::VectorXd MeanFinalPoint(const DemoSet& set) {
  Eigen::VectorXd goal = Eigen::VectorXd::Zero(set.dimension);
  for (const Demonstration& demo : set.demos) goal += demo.position.col(demo.points() - 1);
  return goal / static_cast<double>(set.demos.size());
}

/// The point at arc-length fraction f of the polyline `path` [d x n].
Eigen::VectorXd PointAtArcFraction(const Eigen::MatrixXd& path, double f) {
  const Eigen::Index n = path.cols();
  double length = 0;
  for (Eigen::Index j = 1; j < n; ++j) length += (path.col(j) - path.col(j - 1)).norm();
  if (length <= 0) return path.col(0);
  const double target = f * length;
  double walked = 0;
  for (Eigen::Index j = 1; j < n; ++j) {
    const double seg = (path.col(j) - path.col(j - 1)).norm();
    if (seg > 0 && walked + seg >= target) {
      const double u = std::clamp((target - walked) / seg, 0.0, 1.0);
      return path.col(j - 1) + u * (path.col(j) - path.col(j - 1));
    }
    walked += seg;
  }
  return path.col(n - 1);
}

}  // namespace

GoalSpread CheckDemonstrations(const DemoSet& set, double goal_tolerance) {
  FS_THROW_UNLESS(std::isfinite(goal_tolerance) && goal_tolerance >= 0,
                  "CheckDemonstrations: goal_tolerance must be finite and >= 0, got ",
                  goal_tolerance, " (set '", set.name, "')");
  CheckStructure(set, "CheckDemonstrations", Velocity::kRequired);
  GoalSpread spread;
  spread.goal = MeanFinalPoint(set);
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(set.dimension, INFINITY);
  Eigen::VectorXd hi = Eigen::VectorXd::Constant(set.dimension, -INFINITY);
  std::size_t farthest = 0;
  for (std::size_t i = 0; i < set.demos.size(); ++i) {
    const Demonstration& demo = set.demos[i];
    lo = lo.cwiseMin(demo.position.rowwise().minCoeff());
    hi = hi.cwiseMax(demo.position.rowwise().maxCoeff());
    const double dist = (demo.position.col(demo.points() - 1) - spread.goal).norm();
    if (dist > spread.max_distance) spread.max_distance = dist, farthest = i;
  }
  spread.extent = (hi - lo).maxCoeff();
  FS_THROW_UNLESS(
      spread.max_distance <= goal_tolerance * spread.extent, "CheckDemonstrations: demo set '",
      set.name, "': the final points do not share a goal: demo ", farthest, " ends ",
      spread.max_distance, " from the mean final point, more than goal_tolerance ", goal_tolerance,
      " x extent ", spread.extent, " = ", goal_tolerance * spread.extent);
  return spread;
}

DemoNormalisation FitNormalisation(const DemoSet& set, double half_range) {
  FS_THROW_UNLESS(std::isfinite(half_range) && half_range > 0,
                  "FitNormalisation: half_range must be finite and > 0, got ", half_range,
                  " (set '", set.name, "')");
  CheckStructure(set, "FitNormalisation", Velocity::kIgnored);
  DemoNormalisation n;
  n.offset = MeanFinalPoint(set);
  double radius = 0;
  for (const Demonstration& demo : set.demos)
    radius = std::max(radius, (demo.position.colwise() - n.offset).cwiseAbs().maxCoeff());
  FS_THROW_UNLESS(radius > 0, "FitNormalisation: demo set '", set.name,
                  "': every position is at the goal; nothing to normalise");
  n.scale = half_range / radius;
  return n;
}

DemoSet ApplyNormalisation(const DemoSet& set, const DemoNormalisation& normalisation) {
  CheckStructure(set, "ApplyNormalisation", Velocity::kOptional);
  FS_THROW_UNLESS(normalisation.offset.size() == set.dimension, "ApplyNormalisation: offset has ",
                  normalisation.offset.size(), " entries, demo set '", set.name, "' has dimension ",
                  set.dimension);
  FS_THROW_UNLESS(normalisation.offset.allFinite() && std::isfinite(normalisation.scale) &&
                      normalisation.scale > 0,
                  "ApplyNormalisation: offset must be finite and scale finite and > 0, got scale ",
                  normalisation.scale, " (set '", set.name, "')");
  DemoSet out = set;
  for (Demonstration& demo : out.demos) {
    demo.position = (demo.position.colwise() - normalisation.offset) * normalisation.scale;
    demo.velocity *= normalisation.scale;
  }
  return out;
}

DemoSet Downsample(const DemoSet& set, int stride) {
  FS_THROW_UNLESS(stride >= 1, "Downsample: stride must be >= 1, got ", stride, " (set '", set.name,
                  "')");
  CheckStructure(set, "Downsample", Velocity::kOptional);
  DemoSet out;
  out.name = set.name;
  out.dimension = set.dimension;
  for (std::size_t i = 0; i < set.demos.size(); ++i) {
    const Demonstration& demo = set.demos[i];
    const int n = demo.points();
    std::vector<int> keep;
    for (int j = 0; j < n; j += stride) keep.push_back(j);
    if (keep.back() != n - 1) keep.push_back(n - 1);
    FS_THROW_UNLESS(keep.size() >= 3, "Downsample: stride ", stride, " leaves ", keep.size(),
                    " of the ", n, " points of demo ", i, " of set '", set.name,
                    "' (at least 3 needed)");
    const bool has_velocity = demo.velocity.size() > 0;
    Demonstration d;
    const auto k = static_cast<Eigen::Index>(keep.size());
    d.position.resize(set.dimension, k);
    d.time.resize(k);
    if (has_velocity) d.velocity.resize(set.dimension, k);
    for (Eigen::Index c = 0; c < k; ++c) {
      const int j = keep[static_cast<std::size_t>(c)];
      d.position.col(c) = demo.position.col(j);
      d.time(c) = demo.time(j);
      if (has_velocity) d.velocity.col(c) = demo.velocity.col(j);
    }
    out.demos.push_back(std::move(d));
  }
  return out;
}

void FiniteDifferenceVelocities(DemoSet* set) {
  FS_THROW_UNLESS(set != nullptr, "FiniteDifferenceVelocities: null demo set");
  CheckStructure(*set, "FiniteDifferenceVelocities", Velocity::kIgnored);
  for (Demonstration& demo : set->demos) {
    const Eigen::Index n = demo.position.cols();
    const Eigen::MatrixXd& x = demo.position;
    const Eigen::VectorXd& t = demo.time;
    demo.velocity.setZero(set->dimension, n);
    demo.velocity.col(0) = (x.col(1) - x.col(0)) / (t(1) - t(0));
    for (Eigen::Index j = 1; j + 1 < n; ++j) {
      const double hm = t(j) - t(j - 1), hp = t(j + 1) - t(j);
      demo.velocity.col(j) =
          (hm * hm * (x.col(j + 1) - x.col(j)) + hp * hp * (x.col(j) - x.col(j - 1))) /
          (hm * hp * (hm + hp));
    }
  }
}

std::pair<DemoSet, DemoSet> SplitByDemo(const DemoSet& set, const std::vector<int>& held_out) {
  const int count = static_cast<int>(set.demos.size());
  std::set<int> out;
  for (int i : held_out) {
    FS_THROW_UNLESS(i >= 0 && i < count, "SplitByDemo: held-out index ", i,
                    " is out of range for demo set '", set.name, "' with ", count, " demos");
    FS_THROW_UNLESS(out.insert(i).second, "SplitByDemo: held-out index ", i,
                    " is listed twice (set '", set.name, "')");
  }
  FS_THROW_UNLESS(static_cast<int>(out.size()) < count, "SplitByDemo: holding out ", out.size(),
                  " of the ", count, " demos of set '", set.name, "' leaves none to train on");
  std::pair<DemoSet, DemoSet> split;
  split.first.name = set.name + ":train";
  split.second.name = set.name + ":held_out";
  split.first.dimension = split.second.dimension = set.dimension;
  for (int i = 0; i < count; ++i)
    (out.count(i) ? split.second : split.first).demos.push_back(set.demos[i]);
  return split;
}

Eigen::VectorXd PointAlongDemos(const DemoSet& set, double fraction) {
  FS_THROW_UNLESS(fraction >= 0 && fraction <= 1,
                  "PointAlongDemos: fraction must be in [0, 1], got ", fraction, " (set '",
                  set.name, "')");
  CheckStructure(set, "PointAlongDemos", Velocity::kIgnored);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(set.dimension);
  for (const Demonstration& demo : set.demos) mean += PointAtArcFraction(demo.position, fraction);
  return mean / static_cast<double>(set.demos.size());
}

}  // namespace foresight
