#include "inference/manipulation/fabric.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace foresight::manipulation {
namespace {

using Matrix7 = Eigen::Matrix<double, kDof, kDof>;

/// Step of the central difference of the distance gradient along the sphere velocity, used for
/// the curvature part of J' q_d of the obstacle terms (m).
constexpr double kCurvatureStep = 1e-5;

/// Adds J'M J and J'M (h - J' q_d) of one barrier term; returns whether it was active.
bool AddBarrierTerm(const BarrierParams& p, const ScalarTask& t, Matrix7* M, JointVector* f) {
  const double m = BarrierMetric(p, t.x, t.xd);
  if (m == 0) return false;
  const double h = p.gain * t.xd * t.xd / t.x;
  M->noalias() += m * t.J.transpose() * t.J;
  f->noalias() += (m * (h - t.jdq)) * t.J.transpose();
  return true;
}

/// The obstacle task of a sphere with clearance x and unit normal n at its centre p_W;
/// `gradient(p, &g)` gives the distance gradient at p, for the curvature's central difference.
template <class Gradient>
ScalarTask ObstacleTask(double x, const Eigen::Vector3d& n, const Eigen::Vector3d& p_W,
                        const Gradient& gradient, const PointJacobian& J_p,
                        const Eigen::Vector3d& jdq_p, const JointVector& qd) {
  ScalarTask t;
  t.x = x;
  t.J = n.transpose() * J_p;
  const Eigen::Vector3d v = J_p * qd;
  t.xd = n.dot(v);
  double curvature = 0;
  const double speed = v.norm();
  if (speed > 0) {
    const Eigen::Vector3d u = v / speed;
    Eigen::Vector3d n_plus, n_minus;
    gradient(Eigen::Vector3d(p_W + kCurvatureStep * u), &n_plus);
    gradient(Eigen::Vector3d(p_W - kCurvatureStep * u), &n_minus);
    curvature = speed * speed * u.dot(n_plus - n_minus) / (2 * kCurvatureStep);
  }
  t.jdq = n.dot(jdq_p) + curvature;
  return t;
}

}  // namespace

double BarrierMetric(const BarrierParams& p, double x, double xd) {
  if (xd >= 0 || x >= p.range || x <= 0) return 0;
  return p.metric * (1.0 / x - 1.0 / p.range);
}

ScalarTask SphereObstacleTask(const World& world, const Eigen::Vector3d& p_W, double radius,
                              const PointJacobian& J_p, const Eigen::Vector3d& jdq_p,
                              const JointVector& qd) {
  Eigen::Vector3d n;
  const double clearance = world.SignedDistance(p_W, &n) - radius;
  return ObstacleTask(
      clearance, n, p_W,
      [&](const Eigen::Vector3d& p, Eigen::Vector3d* g) { world.SignedDistance(p, g); }, J_p, jdq_p,
      qd);
}

ScalarTask SphereObstacleTask(const World& world, double signed_distance, int closest,
                              const Eigen::Vector3d& p_W, double radius, const PointJacobian& J_p,
                              const Eigen::Vector3d& jdq_p, const JointVector& qd) {
  Eigen::Vector3d n;
  world.ObstacleSignedDistance(closest, p_W, &n);
  return ObstacleTask(
      signed_distance - radius, n, p_W,
      [&](const Eigen::Vector3d& p, Eigen::Vector3d* g) {
        world.ObstacleSignedDistance(closest, p, g);
      },
      J_p, jdq_p, qd);
}

ScalarTask SpherePairTask(const Eigen::Vector3d& p_a, double r_a, const PointJacobian& J_a,
                          const Eigen::Vector3d& jdq_a, const Eigen::Vector3d& p_b, double r_b,
                          const PointJacobian& J_b, const Eigen::Vector3d& jdq_b,
                          const JointVector& qd) {
  ScalarTask t;
  const Eigen::Vector3d diff = p_a - p_b;
  const double dist = diff.norm();
  t.x = dist - r_a - r_b;
  if (dist <= 0) return t;  // coincident centres: no direction (x < 0 anyway: a collision)
  const Eigen::Vector3d n = diff / dist;
  const PointJacobian J_rel = J_a - J_b;
  const Eigen::Vector3d v = J_rel * qd;
  t.J = n.transpose() * J_rel;
  t.xd = n.dot(v);
  t.jdq = n.dot(jdq_a - jdq_b) + (v.squaredNorm() - t.xd * t.xd) / dist;
  return t;
}

const char* ToString(RolloutStatus status) {
  switch (status) {
    case RolloutStatus::kReached:
      return "reached";
    case RolloutStatus::kTimeout:
      return "timeout";
    case RolloutStatus::kCollision:
      return "collision";
    case RolloutStatus::kJointLimit:
      return "joint_limit";
    case RolloutStatus::kNonFinite:
      return "non_finite";
    case RolloutStatus::kStopped:
      return "stopped";
  }
  return "unknown";
}

Fabric::Fabric(const RobotModel& robot, const World& world, const FabricParams& params)
    : robot_(robot), world_(world), params_(params) {
  FS_THROW_UNLESS(params.dt > 0 && params.t_max >= params.dt,
                  "fabric: dt must be positive and at most t_max (dt ", params.dt, ", t_max ",
                  params.t_max, ")");
  FS_THROW_UNLESS(params.goal_tolerance > 0, "fabric: goal_tolerance must be positive, got ",
                  params.goal_tolerance);
  FS_THROW_UNLESS(params.via_tolerance > 0, "fabric: via_tolerance must be positive, got ",
                  params.via_tolerance);
  FS_THROW_UNLESS(params.stall_window >= 0 && params.stall_progress > 0 &&
                      params.stall_fraction > 0 && params.stall_fraction <= 1,
                  "fabric: stall_window must be >= 0, stall_progress positive and stall_fraction "
                  "in (0, 1], got ",
                  params.stall_window, ", ", params.stall_progress, " and ", params.stall_fraction);
  FS_THROW_UNLESS(params.base_inertia > 0, "fabric: base_inertia must be positive, got ",
                  params.base_inertia);
  BuildBroadPhase();
}

void Fabric::BuildBroadPhase() {
  const auto& spheres = robot_.spheres();
  const int num_spheres = static_cast<int>(spheres.size());
  KinematicsData kin = robot_.MakeData();
  ForwardKinematics(robot_, JointVector::Zero(), &kin);
  // Sphere centres in their body frames, grouped by body.
  std::array<std::vector<int>, kDof + 1> on_body;
  std::vector<Eigen::Vector3d> p_BS(static_cast<std::size_t>(num_spheres));
  for (int s = 0; s < num_spheres; ++s) {
    const int body = robot_.num_supporting_joints(spheres[static_cast<std::size_t>(s)].link);
    on_body[static_cast<std::size_t>(body)].push_back(s);
    p_BS[static_cast<std::size_t>(s)] =
        kin.X_WB[static_cast<std::size_t>(body)].inverse() * Eigen::Vector3d(kin.p_WS.col(s));
  }
  sphere_bound_.assign(static_cast<std::size_t>(num_spheres), -1);
  for (int body = 0; body <= kDof; ++body) {
    const std::vector<int>& members = on_body[static_cast<std::size_t>(body)];
    if (members.empty()) continue;
    BodyBound bound;
    bound.body = body;
    for (int s : members) bound.p_BC += p_BS[static_cast<std::size_t>(s)];
    bound.p_BC /= static_cast<double>(members.size());
    for (int s : members) {
      bound.radius =
          std::max(bound.radius, (p_BS[static_cast<std::size_t>(s)] - bound.p_BC).norm() +
                                     spheres[static_cast<std::size_t>(s)].radius);
      sphere_bound_[static_cast<std::size_t>(s)] = static_cast<int>(body_bounds_.size());
    }
    // Rounding of the centre's transform and of the distances (m): a bound never skips a sphere
    // it should have kept.
    bound.radius += 1e-9;
    body_bounds_.push_back(bound);
  }
  pair_runs_.clear();
  const auto& pairs = robot_.self_collision_pairs();
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const auto [a, b] = pairs[i];
    const int other = sphere_bound_[static_cast<std::size_t>(b)];
    if (pair_runs_.empty() || pair_runs_.back().sphere != a ||
        pair_runs_.back().other_bound != other)
      pair_runs_.push_back({static_cast<int>(i), static_cast<int>(i), a, other});
    ++pair_runs_.back().end;
  }
}

FabricWorkspace Fabric::MakeWorkspace() const {
  FabricWorkspace ws{robot_.MakeData(), {}, {}, {}};
  const auto n = static_cast<std::size_t>(world_.num_obstacles());
  ws.bound_distances.resize(n);
  ws.candidates.resize(static_cast<std::size_t>(kDof + 1) * n);
  return ws;
}

void Fabric::SelectObstacles(const std::array<Eigen::Vector3d, kDof + 1>& c_W, FabricWorkspace* ws,
                             std::array<int, kDof + 1>* count) const {
  const int num_obstacles = world_.num_obstacles();
  FS_THROW_UNLESS(static_cast<int>(ws->bound_distances.size()) == num_obstacles &&
                      ws->candidates.size() == static_cast<std::size_t>((kDof + 1) * num_obstacles),
                  "fabric: the workspace was made for another world (use this fabric's "
                  "MakeWorkspace)");
  const int num_bounds = static_cast<int>(body_bounds_.size());
  if (num_obstacles == 0) return;
  if (!params_.broad_phase) {
    for (int k = 0; k < num_bounds; ++k) (*count)[static_cast<std::size_t>(k)] = num_obstacles;
    return;
  }
  const Eigen::AlignedBox3d& bounds = world_.bounds();
  for (int k = 0; k < num_bounds; ++k) {
    const double reach = params_.obstacles.range + body_bounds_[static_cast<std::size_t>(k)].radius;
    const Eigen::Vector3d& c = c_W[static_cast<std::size_t>(k)];
    if (bounds.exteriorDistance(c) > reach) continue;
    ++ws->probe.obstacle_distances;
    world_.ObstacleDistances(c, ws->bound_distances.data());
    int* candidates = ws->candidates.data() + static_cast<std::ptrdiff_t>(k) * num_obstacles;
    int& n = (*count)[static_cast<std::size_t>(k)];
    for (int i = 0; i < num_obstacles; ++i)
      if (!(ws->bound_distances[static_cast<std::size_t>(i)] > reach)) candidates[n++] = i;
  }
}

bool Fabric::Acceleration(const JointVector& q, const JointVector& qd, const JointVector& command,
                          FabricWorkspace* ws, JointVector* qdd) const {
  const FabricParams& p = params_;
  KinematicsData& kin = ws->kinematics;
  ForwardKinematicsWithJacobians(robot_, q, qd, &kin);

  Matrix7 M = p.base_inertia * Matrix7::Identity();
  JointVector f = JointVector::Zero();
  FabricProbe& probe = ws->probe;
  probe = FabricProbe{};
  probe.min_obstacle_clearance = std::numeric_limits<double>::infinity();
  probe.min_self_clearance = std::numeric_limits<double>::infinity();

  // Joint limits: x = q_j - lower_j (J = e_j) and x = upper_j - q_j (J = -e_j); J' q_d = 0.
  const JointLimits& limits = robot_.limits();
  for (int j = 0; j < kDof; ++j) {
    const double m_lo = BarrierMetric(p.limits, q[j] - limits.lower[j], qd[j]);
    if (m_lo > 0) {
      const double x = q[j] - limits.lower[j];
      M(j, j) += m_lo;
      f[j] += m_lo * p.limits.gain * qd[j] * qd[j] / x;
    }
    const double m_hi = BarrierMetric(p.limits, limits.upper[j] - q[j], -qd[j]);
    if (m_hi > 0) {
      const double x = limits.upper[j] - q[j];
      M(j, j) += m_hi;
      f[j] -= m_hi * p.limits.gain * qd[j] * qd[j] / x;
    }
  }

  // Body spheres vs the world (closest obstacle) and checked sphere pairs. The broad phase
  // first (FabricProbe): a body's spheres against the obstacles within its bound's reach, a run
  // of pairs only when its sphere is within reach of the other body's bound; then the cheap
  // distance test; the pull-back only for terms within range. Spheres and pairs keep their
  // order, so the sums are those of the full loops.
  const auto& spheres = robot_.spheres();
  const int num_spheres = static_cast<int>(spheres.size());
  const int num_bounds = static_cast<int>(body_bounds_.size());
  std::array<Eigen::Vector3d, kDof + 1> c_W;  // bounding-sphere centres in W
  for (int k = 0; k < num_bounds; ++k) {
    const BodyBound& bound = body_bounds_[static_cast<std::size_t>(k)];
    c_W[static_cast<std::size_t>(k)] = kin.X_WB[static_cast<std::size_t>(bound.body)] * bound.p_BC;
  }
  std::array<int, kDof + 1> num_candidates{};
  SelectObstacles(c_W, ws, &num_candidates);
  const int num_obstacles = world_.num_obstacles();
  const Eigen::AlignedBox3d& bounds = world_.bounds();
  for (int s = 0; s < num_spheres; ++s) {
    const int k = sphere_bound_[static_cast<std::size_t>(s)];
    const int count = num_candidates[static_cast<std::size_t>(k)];
    if (count == 0) continue;
    const double cutoff = p.obstacles.range + spheres[s].radius;
    if (bounds.exteriorDistance(Eigen::Vector3d(kin.p_WS.col(s))) > cutoff) continue;
    int closest = -1;
    ++probe.obstacle_distances;
    // All obstacles: the world's SIMD minimum; a few: those alone (the same numbers).
    const double d =
        count == num_obstacles
            ? world_.SignedDistance(kin.p_WS.col(s), nullptr, &closest)
            : world_.SignedDistanceAmong(
                  kin.p_WS.col(s),
                  ws->candidates.data() + static_cast<std::ptrdiff_t>(k) * num_obstacles, count,
                  nullptr, &closest);
    const double x = d - spheres[s].radius;
    probe.min_obstacle_clearance = std::min(probe.min_obstacle_clearance, x);
    if (!(x < p.obstacles.range) || x <= 0) continue;
    const ScalarTask t = SphereObstacleTask(world_, d, closest, kin.p_WS.col(s), spheres[s].radius,
                                            kin.J_WS[s], kin.Jdot_qdot_WS[s], qd);
    probe.active_obstacle_terms += AddBarrierTerm(p.obstacles, t, &M, &f);
  }
  const auto& pairs = robot_.self_collision_pairs();
  double min_self_clearance = std::numeric_limits<double>::infinity();
  for (const PairRun& run : pair_runs_) {
    if (p.broad_phase) {
      const double reach = p.self.range + spheres[run.sphere].radius +
                           body_bounds_[static_cast<std::size_t>(run.other_bound)].radius;
      if ((kin.p_WS.col(run.sphere) - c_W[static_cast<std::size_t>(run.other_bound)]).norm() >
          reach)
        continue;
    }
    probe.pair_distances += run.end - run.begin;
    for (int i = run.begin; i < run.end; ++i) {
      const auto [a, b] = pairs[static_cast<std::size_t>(i)];
      const double reach = spheres[a].radius + spheres[b].radius;
      const double x = (kin.p_WS.col(a) - kin.p_WS.col(b)).norm() - reach;
      min_self_clearance = std::min(min_self_clearance, x);
      if (!(x < p.self.range) || x <= 0) continue;
      const ScalarTask t =
          SpherePairTask(kin.p_WS.col(a), spheres[a].radius, kin.J_WS[a], kin.Jdot_qdot_WS[a],
                         kin.p_WS.col(b), spheres[b].radius, kin.J_WS[b], kin.Jdot_qdot_WS[b], qd);
      probe.active_self_terms += AddBarrierTerm(p.self, t, &M, &f);
    }
  }
  probe.min_self_clearance = min_self_clearance;

  // Attractor: metric, forcing and damping towards the command.
  const JointVector x_c = q - command;
  const double r = x_c.norm();
  const double m_psi = p.attractor_metric_far + (p.attractor_metric_near - p.attractor_metric_far) *
                                                    std::exp(-(r / p.attractor_metric_width) *
                                                             (r / p.attractor_metric_width));
  M.diagonal().array() += m_psi;
  JointVector grad_psi = JointVector::Zero();
  if (r > 0) grad_psi = (p.attractor_gain * std::tanh(p.attractor_sharpness * r) / r) * x_c;
  const double beta = p.damping + p.damping_near / (1.0 + (r / p.damping_near_radius) *
                                                              (r / p.damping_near_radius));

  probe.metric = M;
  const Eigen::LLT<Matrix7> llt(M);
  if (llt.info() != Eigen::Success) return false;
  JointVector a_geometry = llt.solve(f);
  const double speed_sq = qd.squaredNorm();
  if (speed_sq > 1e-12) a_geometry -= qd * (qd.dot(a_geometry) / speed_sq);  // Energize, M_e = I
  probe.energized = a_geometry;
  const JointVector result = a_geometry - llt.solve(grad_psi) - beta * qd;
  if (!result.allFinite()) return false;
  *qdd = result;
  return true;
}

RolloutResult Fabric::Rollout(const JointVector& q0, const JointVector& qd0,
                              const JointVector& command, FabricWorkspace* ws,
                              std::vector<JointVector>* path, double stop_beyond_s,
                              CommandRole role) const {
  const FabricParams& p = params_;
  const double tolerance = role == CommandRole::kVia ? p.via_tolerance : p.goal_tolerance;
  const JointLimits& limits = robot_.limits();
  const int max_steps = static_cast<int>(std::llround(p.t_max / p.dt));
  RolloutResult result;
  result.q = q0;
  result.qd = qd0;
  if (!q0.allFinite() || !qd0.allFinite() || !command.allFinite()) {
    result.status = RolloutStatus::kNonFinite;
    return result;
  }
  // Stall test, towards the goal only: an intermediate rollout's end state starts the next one,
  // so ending it early would change what follows. The step of the last progress and its distance.
  const int stall_steps = p.stall_window > 0 && role == CommandRole::kGoal
                              ? std::max(1, static_cast<int>(std::llround(p.stall_window / p.dt)))
                              : 0;
  double anchor = std::numeric_limits<double>::infinity();
  int anchor_step = 0;
  JointVector qdd;
  for (int step = 0;; ++step) {
    result.steps = step;
    result.t = step * p.dt;
    if (!Acceleration(result.q, result.qd, command, ws, &qdd)) {
      result.status = RolloutStatus::kNonFinite;
      return result;
    }
    if (ws->probe.min_obstacle_clearance < 0 || ws->probe.min_self_clearance < 0) {
      result.status = RolloutStatus::kCollision;
      return result;
    }
    const double distance = (result.q - command).norm();
    if (distance < tolerance) {
      result.status = RolloutStatus::kReached;
      return result;
    }
    if (step >= max_steps) {
      result.status = RolloutStatus::kTimeout;
      return result;
    }
    if (result.t > stop_beyond_s) {
      result.status = RolloutStatus::kStopped;
      return result;
    }
    if (stall_steps > 0) {
      const double needed = std::min(p.stall_progress, p.stall_fraction * (anchor - tolerance));
      if (distance < anchor - needed) {
        anchor = distance;
        anchor_step = step;
      } else if (step - anchor_step >= stall_steps) {
        // Charged as the timeout it is taken for; a caller's time limit still comes first.
        result.t = max_steps * p.dt;
        result.stalled = true;
        result.status =
            result.t > stop_beyond_s ? RolloutStatus::kStopped : RolloutStatus::kTimeout;
        return result;
      }
    }
    result.qd += p.dt * qdd;
    result.q += p.dt * result.qd;
    if (path) path->push_back(result.q);
    if ((result.q.array() < limits.lower.array()).any() ||
        (result.q.array() > limits.upper.array()).any()) {
      result.steps = step + 1;
      result.t = result.steps * p.dt;
      result.status = RolloutStatus::kJointLimit;
      return result;
    }
  }
}

}  // namespace foresight::manipulation
