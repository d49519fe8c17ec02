#pragma once
/// Shared pieces of the diffeomorphic-templates evaluation (eval_planar.cc, eval_task_space.cc):
/// path sets and their scores, start grids, the obstacle map and the outer transforms.
/// Torch-free.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "inference/imitation/metrics.h"
#include "inference/imitation/transforms.h"
#include "models/imitation/occupancy_fit.h"
#include "training/diffeo/config.h"
#include "training/diffeo/demos.h"
#include "training/diffeo/eval.h"

namespace foresight::imitation {

/// The rollouts of a template in its normalised coordinates (eval.dt, max_steps, goal_tolerance,
/// max_step_length): the evaluation's and the flow restarts' choice's.
inline RolloutSettings ModelRollouts(const ExperimentConfig& c) {
  RolloutSettings r;
  r.dt = c.eval.dt;
  r.max_steps = c.eval.max_steps;
  r.goal_tolerance = c.eval.goal_tolerance;
  r.max_step_length = c.eval.max_step_length;
  return r;
}

/// How well one obstacle setting (flow time, repulsor gain) keeps rollouts off the map's obstacle.
struct Clearance {
  bool training_clear = false;  ///< every training start reaches the goal with p < clear
  int grid_crossing = 0;  ///< grid starts whose rollout reaches p >= clear (0 when not counted)
};

/// The selection among obstacle settings tried in order (docs/diffeo.md "Selection"): the first
/// whose training starts are clear and whose grid crossings are the fewest of those; with no
/// training-clear setting, the last one tried. Returns its index; `tried` must not be empty.
inline std::size_t ChooseClearance(const std::vector<Clearance>& tried) {
  std::size_t best = tried.size() - 1;
  bool found = false;
  for (std::size_t i = 0; i < tried.size(); ++i)
    if (tried[i].training_clear && (!found || tried[i].grid_crossing < tried[best].grid_crossing)) {
      best = i;
      found = true;
    }
  return best;
}

/// One obstacle-flow time tried at one Euler step: whether its map inverts (along the rollouts)
/// and whether its rollouts from the training starts are clear of the map.
struct FlowTrial {
  bool inverts = false;
  bool clear = false;
};

/// The time (and step) a task-space obstacle flow runs with.
struct FlowTimeChoice {
  int index = -1;        ///< into `times`; -1: the first time does not invert at any step tried
  double step = 0;       ///< its Euler step
  bool cleared = false;  ///< its training rollouts are clear
};

/// Task-space obstacle-flow selection: the times in order, each at the current step and, while its
/// map does not invert, at the step halved (at most `halvings` halvings in all; a halved step is
/// kept for the larger times); stops at the first time that clears (chosen) or that does not
/// invert at any step left (the previous one is chosen).
inline FlowTimeChoice ChooseFlowTime(const std::vector<double>& times, double step, int halvings,
                                     const std::function<FlowTrial(double, double)>& trial) {
  FlowTimeChoice out;
  for (std::size_t i = 0; i < times.size(); ++i) {
    FlowTrial t = trial(times[i], step);
    while (!t.inverts && halvings > 0) {
      step /= 2;
      --halvings;
      t = trial(times[i], step);
    }
    if (!t.inverts) break;  // larger times only bend the map further
    out = {static_cast<int>(i), step, t.clear};
    if (t.clear) break;
  }
  return out;
}

/// Rolled-out paths [d x n_k] with whether each reached the goal.
struct PathSet {
  std::vector<Eigen::MatrixXd> paths;
  std::vector<char> reached;
};

template <int D>
PathSet ToPaths(const std::vector<Rollout<D>>& rollouts) {
  PathSet p;
  for (const auto& r : rollouts) {
    p.paths.push_back(r.path);
    p.reached.push_back(r.reached && r.finite ? 1 : 0);
  }
  return p;
}

template <int D>
double ReachRate(const std::vector<Rollout<D>>& rollouts) {
  if (rollouts.empty()) return 0;
  double n = 0;
  for (const auto& r : rollouts) n += (r.reached && r.finite) ? 1 : 0;
  return n / static_cast<double>(rollouts.size());
}

/// prefix + frechet (mean over the paths), frechet_heldout (mean over paths from held-out demos,
/// when there are any) and reach_rate. Path k starts at demo ids[k] (all demos when ids is empty)
/// and is compared with it after both are resampled to `resample` points by arc length.
/// `scale` converts to the reported unit (1: normalised; 1 / norm.scale: data units).
void AddPathScores(const std::string& prefix, const PathSet& paths, const PreparedDemos& demos,
                   int resample, Scores* s, const std::vector<int>& ids = {}, double scale = 1.0);

/// g^D starts on a regular grid over the demonstrations' box grown by `margin` on every side.
template <int D>
std::vector<Vec<D>> GridStarts(const DemoSet& set, int g, double margin) {
  Eigen::Matrix<double, D, 1> lo = Eigen::Matrix<double, D, 1>::Constant(1e300), hi = -lo;
  for (const Demonstration& d : set.demos) {
    lo = lo.cwiseMin(d.position.rowwise().minCoeff());
    hi = hi.cwiseMax(d.position.rowwise().maxCoeff());
  }
  lo.array() -= margin;
  hi.array() += margin;
  std::vector<Vec<D>> out;
  int total = 1;
  for (int a = 0; a < D; ++a) total *= g;
  for (int k = 0; k < total; ++k) {
    Vec<D> p;
    int r = k;
    for (int a = 0; a < D; ++a) {
      p[a] = lo[a] + (hi[a] - lo[a]) * (r % g) / (g - 1.0);
      r /= g;
    }
    out.push_back(p);
  }
  return out;
}

/// The starts outside an obstacle.
template <int D, class Obstacle>
std::vector<Vec<D>> FreeOf(const std::vector<Vec<D>>& starts, const Obstacle& o) {
  std::vector<Vec<D>> out;
  for (const auto& p : starts)
    if (o.SignedDistance(p) > 0) out.push_back(p);
  return out;
}

/// MCD of point paths against an obstacle (points, body radius 0).
template <class Obstacle>
double MaxDepth(const PathSet& paths, const Obstacle& o, double scale = 1.0) {
  double worst = 0;
  for (const Eigen::MatrixXd& p : paths.paths)
    worst = std::max(worst, MaxCollisionDepth(p, o, 0.0));
  return worst * scale;
}

/// The occupancy map of an obstacle: a Hilbert map on a grid around it, fitted on a lattice of
/// labelled samples (exact signed distance <= 0 is occupied).
template <int D>
OccupancyField<D> FitObstacleMap(const ObstacleConfig& o,
                                 const std::function<double(const Vec<D>&)>& signed_distance,
                                 const Vec<D>& lo_in, const Vec<D>& hi_in,
                                 const std::string& source) {
  const Vec<D> lo = lo_in.array() - o.sample_margin;
  const Vec<D> hi = hi_in.array() + o.sample_margin;
  Eigen::Matrix<double, D, Eigen::Dynamic> points;
  std::vector<std::uint8_t> occupied;
  // Labels from the obstacle grown by map_inflate: a margin between the map's boundary and the
  // exact obstacle the metrics use.
  SampleObstacleOccupancy<D>([&](const Vec<D>& p) { return signed_distance(p) - o.map_inflate; },
                             lo, hi, o.sample_spacing, &points, &occupied);
  const RbfGrid<D> grid(RbfGrid<D>::Covering(lo, hi, 0.0, o.map_spacing, o.map_gamma, o.map_cutoff),
                        source + ": obstacle map");
  return FitOccupancyField<D>(grid, points, occupied, o.map_l2, source + ": obstacle map");
}

/// The same for a ball-shaped 2-D obstacle given by its centre and radius.
template <int D>
OccupancyField<D> FitObstacleMap(const ObstacleConfig& o,
                                 const std::function<double(const Vec<D>&)>& signed_distance,
                                 const Vec<D>& centre, double radius, const std::string& source) {
  return FitObstacleMap<D>(o, signed_distance, Vec<D>(centre.array() - radius),
                           Vec<D>(centre.array() + radius), source);
}

/// Largest |grad p| and spectral norm of Hess p of a map on a lattice over [lo, hi].
template <int D>
std::pair<double, double> MapSlopes(const OccupancyField<D>& field, const Vec<D>& lo,
                                    const Vec<D>& hi, double spacing) {
  auto ws = field.MakeWorkspace();
  std::array<int, D> n{};
  int total = 1;
  for (int a = 0; a < D; ++a) {
    n[a] = std::max(2, static_cast<int>(std::ceil((hi[a] - lo[a]) / spacing)) + 1);
    total *= n[a];
  }
  double g = 0, h = 0;
  OccupancyValue<D> v;
  for (int k = 0; k < total; ++k) {
    Vec<D> y;
    int r = k;
    for (int a = 0; a < D; ++a) {
      y[a] = lo[a] + (hi[a] - lo[a]) * (r % n[a]) / (n[a] - 1.0);
      r /= n[a];
    }
    field.Evaluate(y, ws.get(), true, &v);
    g = std::max(g, v.gradient.norm());
    h = std::max(
        h, v.hessian.template selfadjointView<Eigen::Lower>().eigenvalues().cwiseAbs().maxCoeff());
  }
  return {g, h};
}

/// The Euler step of an obstacle flow: obstacle.step, or less where the map is steeper, so that
/// h ||Hess p|| <= obstacle.step_lipschitz (< 1: each step a perturbed identity, invertible).
inline double ObstacleStep(const ObstacleConfig& o, double max_hessian) {
  return std::min(o.step, o.step_lipschitz / std::max(max_hessian, 1e-12));
}

/// Euler steps of an obstacle flow of time `time` with step h: ceil(time / h).
inline int ObstacleSteps(double time, double h) {
  return std::max(1, static_cast<int>(std::ceil(time / h - 1e-9)));
}

template <int D>
OuterTransform<D> ObstacleOuter(const OccupancyField<D>& field, double time, double h,
                                ObstacleGate<D> gate = {}) {
  OuterTransform<D> t;
  t.type = OuterTransform<D>::Type::kObstacle;
  FlowSettings<D> fs;
  fs.time = time;
  fs.steps = ObstacleSteps(time, h);
  t.obstacle = ObstacleTransform<D>(field, fs, gate);
  return t;
}

/// Whether psi_o^-1(psi_o(y)) = y (to `tolerance`) on a lattice of spacing `spacing` over [lo, hi]:
/// the settings keep the Euler map invertible there.
template <int D>
bool ObstacleInvertible(const ObstacleTransform<D>& t, const Vec<D>& lo, const Vec<D>& hi,
                        double spacing, double tolerance) {
  auto ws = t.MakeWorkspace();
  std::array<int, D> n{};
  int total = 1;
  for (int a = 0; a < D; ++a) {
    n[a] = std::max(2, static_cast<int>(std::ceil((hi[a] - lo[a]) / spacing)) + 1);
    total *= n[a];
  }
  for (int k = 0; k < total; ++k) {
    Vec<D> y;
    int r = k;
    for (int a = 0; a < D; ++a) {
      y[a] = lo[a] + (hi[a] - lo[a]) * (r % n[a]) / (n[a] - 1.0);
      r /= n[a];
    }
    Vec<D> back;
    if (!t.Inverse(t.Forward(y, ws.get()), ws.get(), &back) || (back - y).norm() > tolerance)
      return false;
  }
  return true;
}

/// The bias transform toward `target`: samples on a lattice within bias.region of it.
template <int D>
RbfFlow<D> FitBias(const BiasConfig& b, const RbfGridSpec<D>& spec, const Vec<D>& target) {
  std::vector<Vec<D>> samples;
  const RbfGrid<D> grid(spec, "bias grid");
  for (int t = 0; t < grid.size(); ++t)
    if ((grid.Centre(t) - target).norm() <= b.region) samples.push_back(grid.Centre(t));
  FS_THROW_UNLESS(samples.size() >= 2, "bias.region (", b.region,
                  ") holds fewer than 2 inducing states around the target");
  Eigen::Matrix<double, D, Eigen::Dynamic> m(D, static_cast<Eigen::Index>(samples.size()));
  for (std::size_t i = 0; i < samples.size(); ++i) m.col(static_cast<Eigen::Index>(i)) = samples[i];
  FlowSettings<D> fs;
  fs.time = b.time;
  fs.steps = b.steps;
  return FitBiasTransform<D>(grid, m, target, 1e-6, fs);
}

/// Where the obstacle goes: the point at arc-length share `fraction` of the first training
/// demonstration (on a demonstrated path even when the demos are of different shapes, as in
/// LASA's Multi_Models, whose mean path can pass through the goal).
inline Eigen::VectorXd ObstacleCentre(const PreparedDemos& demos, double fraction) {
  DemoSet first;
  first.name = demos.demos.name;
  first.dimension = demos.demos.dimension;
  first.demos.push_back(demos.demos.demos[static_cast<std::size_t>(demos.train.front())]);
  return PointAlongDemos(first, fraction);
}

/// `count` points from a to b.
inline Eigen::MatrixXd LinePath(const Eigen::VectorXd& a, const Eigen::VectorXd& b, int count) {
  Eigen::MatrixXd p(a.size(), count);
  for (int k = 0; k < count; ++k) p.col(k) = a + (b - a) * (k / (count - 1.0));
  return p;
}

/// The smallest distance of any path point to `target`.
inline double ClosestApproach(const PathSet& paths, const Eigen::VectorXd& target) {
  double best = 1e300;
  for (const Eigen::MatrixXd& p : paths.paths)
    best = std::min(best, (p.colwise() - target).colwise().norm().minCoeff());
  return best;
}

}  // namespace foresight::imitation
