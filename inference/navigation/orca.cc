#include "inference/navigation/orca.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/error.h"
#include "core/geometry2d.h"
#include "inference/navigation/span_controller.h"

namespace foresight::nav {

namespace {

constexpr double kEps = 1e-9;

/// Direction of the boundary line of a half-plane (the normal turned by -90 degrees).
Eigen::Vector2d AlongLine(const Eigen::Vector2d& normal) { return {normal.y(), -normal.x()}; }

/// The 1-D problem on the boundary line of planes[i], within the disc of radius `max_speed` and
/// the half-planes planes[0, i). Quadratic objective (closest to `target`) or, when `linear`,
/// maximise x . target. @return false when the line has no point satisfying them all.
bool SolveOnLine(const std::vector<OrcaHalfPlane>& planes, std::size_t i, double max_speed,
                 const Eigen::Vector2d& target, bool linear, Eigen::Vector2d* x) {
  const OrcaHalfPlane& h = planes[i];
  const Eigen::Vector2d d = AlongLine(h.normal);
  // x(t) = point + t d inside the disc: t^2 + 2 t (point.d) + |point|^2 - R^2 <= 0.
  const double pd = h.point.dot(d);
  const double discriminant = pd * pd - h.point.squaredNorm() + max_speed * max_speed;
  if (discriminant < 0) return false;
  const double root = std::sqrt(discriminant);
  double lo = -pd - root, hi = -pd + root;
  for (std::size_t j = 0; j < i; ++j) {
    // (point + t d - point_j) . normal_j >= 0  <=>  t (d . normal_j) >= (point_j - point) .
    // normal_j
    const double den = d.dot(planes[j].normal);
    const double num = (planes[j].point - h.point).dot(planes[j].normal);
    if (std::abs(den) < kEps) {
      if (num > kEps) return false;  // parallel, and the whole line is outside plane j
      continue;
    }
    if (den > 0)
      lo = std::max(lo, num / den);
    else
      hi = std::min(hi, num / den);
    if (lo > hi + kEps) return false;
  }
  if (lo > hi) lo = hi = 0.5 * (lo + hi);
  double t;
  if (linear) {
    const double slope = d.dot(target);
    t = slope > kEps ? hi : slope < -kEps ? lo : std::clamp(-pd, lo, hi);
  } else {
    t = std::clamp(d.dot(target - h.point), lo, hi);
  }
  *x = h.point + t * d;
  return true;
}

/// The 2-D incremental program over `planes` and the disc: closest to `target` (quadratic) or the
/// largest x . target (linear; `target` a unit vector). Each violated plane moves the optimum onto
/// its line. @return the index of the first plane that cannot be met (planes.size(): all met).
std::size_t Program2(const std::vector<OrcaHalfPlane>& planes, double max_speed,
                     const Eigen::Vector2d& target, bool linear, Eigen::Vector2d* x) {
  if (linear) {
    *x = max_speed * target;
  } else {
    const double norm = target.norm();
    *x = norm > max_speed ? Eigen::Vector2d(target * (max_speed / norm)) : target;
  }
  for (std::size_t i = 0; i < planes.size(); ++i) {
    if (planes[i].Margin(*x) >= -kEps) continue;
    Eigen::Vector2d y;
    if (!SolveOnLine(planes, i, max_speed, target, linear, &y)) return i;
    *x = y;
  }
  return planes.size();
}

/// The 3-D fallback: min over x in the disc of the largest violation max_j -(x - q_j) . n_j.
/// planes[0, begin) are met by `*x` (the 2-D program's last optimum). Incremental as Program2:
/// when plane i is violated by more than the current optimum d, the new optimum has plane i's
/// violation as the largest, so every earlier plane j must satisfy
///   (x - q_j) . n_j >= (x - q_i) . n_i  <=>  x . (n_j - n_i) >= q_j . n_j - q_i . n_i,
/// and the violation of plane i is minimised (x . n_i maximised) subject to those: a 2-D program
/// with a linear objective.
void Program3(const std::vector<OrcaHalfPlane>& planes, std::size_t begin, double max_speed,
              std::vector<OrcaHalfPlane>* projected, Eigen::Vector2d* x) {
  double worst = 0;
  for (std::size_t i = begin; i < planes.size(); ++i) {
    if (-planes[i].Margin(*x) <= worst + kEps) continue;
    projected->clear();
    const OrcaHalfPlane& hi = planes[i];
    for (std::size_t j = 0; j < i; ++j) {
      const OrcaHalfPlane& hj = planes[j];
      const Eigen::Vector2d m = hj.normal - hi.normal;
      const double m2 = m.squaredNorm();
      // Same direction: plane j's violation minus plane i's is a constant, <= 0 here (plane j
      // was not violated more than `worst` while plane i is): it never binds.
      if (m2 < kEps * kEps) continue;
      const double c = hj.point.dot(hj.normal) - hi.point.dot(hi.normal);
      OrcaHalfPlane p;
      p.normal = m / std::sqrt(m2);
      p.point = m * (c / m2);
      projected->push_back(p);
    }
    Eigen::Vector2d y;
    // Numerically the program can fail by a hair; keep the previous optimum then.
    if (Program2(*projected, max_speed, hi.normal, true, &y) == projected->size()) *x = y;
    worst = std::max(worst, -planes[i].Margin(*x));
  }
}

}  // namespace

OrcaHalfPlane OrcaConstraint(const Eigen::Vector2d& position, const Eigen::Vector2d& velocity,
                             double radius, const OrcaNeighbour& neighbour,
                             const OrcaOptions& options) {
  const Eigen::Vector2d p = neighbour.position - position;  // relative position
  const Eigen::Vector2d v = velocity - neighbour.velocity;  // relative velocity
  const double r = radius + neighbour.radius, dist2 = p.squaredNorm(), r2 = r * r;
  const Eigen::Vector2d away =
      dist2 > kEps * kEps ? Eigen::Vector2d(-p / std::sqrt(dist2)) : Eigen::Vector2d::UnitX();
  Eigen::Vector2d u, n;  // smallest change onto the boundary of VO, outward normal there
  if (dist2 > r2) {
    const double inv_tau = 1.0 / options.time_horizon;
    const Eigen::Vector2d w = v - inv_tau * p;  // from the cut-off centre p / tau to v
    const double wp = w.dot(p), w2 = w.squaredNorm();
    if (wp < 0 && wp * wp > r2 * w2) {
      // The closest boundary point lies on the cut-off arc (radius r / tau around p / tau).
      const double wn = std::sqrt(w2);
      n = wn > kEps ? Eigen::Vector2d(w / wn) : Eigen::Vector2d(-away);
      u = (r * inv_tau - wn) * n;
    } else {
      // On a leg: the tangent from the origin to D(p, r), p turned by +-asin(r / |p|).
      const double leg = std::sqrt(dist2 - r2);
      Eigen::Vector2d dir;
      if (p.x() * w.y() - p.y() * w.x() > 0) {  // v left of p: the left leg
        dir = Eigen::Vector2d(p.x() * leg - p.y() * r, p.x() * r + p.y() * leg) / dist2;
        n = Eigen::Vector2d(-dir.y(), dir.x());  // the cone lies clockwise of the left leg
      } else {
        dir = Eigen::Vector2d(p.x() * leg + p.y() * r, -p.x() * r + p.y() * leg) / dist2;
        n = Eigen::Vector2d(dir.y(), -dir.x());
      }
      u = v.dot(dir) * dir - v;
    }
  } else {
    // Overlapping: the cut-off disc of one time step, D(p / dt, r / dt); v is inside it.
    const double inv_dt = 1.0 / options.dt;
    const Eigen::Vector2d w = v - inv_dt * p;
    const double wn = w.norm();
    n = wn > kEps ? Eigen::Vector2d(w / wn) : away;
    u = (r * inv_dt - wn) * n;
  }
  OrcaHalfPlane h;
  h.point = velocity + neighbour.responsibility * u;
  h.normal = n;
  return h;
}

bool OrcaClosestFeasible(const std::vector<OrcaHalfPlane>& planes, double max_speed,
                         const Eigen::Vector2d& preferred, Eigen::Vector2d* x) {
  return Program2(planes, max_speed, preferred, false, x) == planes.size();
}

OrcaResult OrcaVelocity(const Eigen::Vector2d& position, const Eigen::Vector2d& velocity,
                        double radius, const Eigen::Vector2d& preferred,
                        const std::vector<OrcaNeighbour>& neighbours, const OrcaOptions& options,
                        OrcaWorkspace* workspace) {
  OrcaWorkspace local;
  OrcaWorkspace& ws = workspace ? *workspace : local;
  ws.planes.clear();
  for (const OrcaNeighbour& nb : neighbours)
    ws.planes.push_back(OrcaConstraint(position, velocity, radius, nb, options));
  OrcaResult out;
  const double speed = std::max(options.max_speed, 0.0);
  const std::size_t failed = Program2(ws.planes, speed, preferred, false, &out.velocity);
  if (failed < ws.planes.size()) {
    out.feasible = false;
    Program3(ws.planes, failed, speed, &ws.projected, &out.velocity);
  }
  const double norm = out.velocity.norm();
  if (norm > speed) out.velocity *= speed / norm;  // rounding on the disc's boundary
  if (!out.velocity.allFinite()) out.velocity.setZero();
  for (const OrcaHalfPlane& h : ws.planes)
    out.max_violation = std::max(out.max_violation, -h.Margin(out.velocity));
  return out;
}

// ---- the controller ----------------------------------------------------------------------------

std::string OrcaControllerOptions::Problems() const {
  std::ostringstream e;
  if (!(time_horizon > 0)) e << "time_horizon = " << time_horizon << " must be > 0; ";
  if (!(responsibility > 0 && responsibility <= 1))
    e << "responsibility = " << responsibility << " must be in (0, 1]; ";
  if (!(heading_gain > 0)) e << "heading_gain = " << heading_gain << " must be > 0; ";
  if (!(safety_margin >= 0)) e << "safety_margin = " << safety_margin << " must be >= 0; ";
  if (!(dt > 0)) e << "dt = " << dt << " must be > 0; ";
  if (!(robot_radius > 0)) e << "robot_radius = " << robot_radius << " must be > 0; ";
  if (!(pedestrian_radius >= 0))
    e << "pedestrian_radius = " << pedestrian_radius << " must be >= 0; ";
  if (!(epsilon > 0 && epsilon < 1)) e << "epsilon = " << epsilon << " must be in (0, 1); ";
  if (!(limits.v_max > 0)) e << "limits.v_max = " << limits.v_max << " must be > 0; ";
  if (!(limits.omega_max > 0)) e << "limits.omega_max = " << limits.omega_max << " must be > 0; ";
  return e.str();
}

OrcaController::OrcaController(const StaticCollisionField* field, OrcaControllerOptions options)
    : field_(field), options_(std::move(options)) {
  const std::string problems = options_.Problems();
  FS_THROW_UNLESS(problems.empty(), "ORCA controller options: ", problems);
  if (field_ && field_->empty()) field_ = nullptr;
  if (field_) map_ws_ = field_->MakeWorkspace();
}

void OrcaController::Prepare(const Eigen::Vector2d& goal) {
  if (field_ && (goal_field_.empty() || goal_field_.goal() != goal))
    goal_field_ = GoalDistanceField(*field_, goal, options_.epsilon);
}

Eigen::Vector2d OrcaController::PreferredVelocity(const Eigen::Vector2d& x,
                                                  const Eigen::Vector2d& goal) const {
  const Eigen::Vector2d to_goal = goal - x;
  const double distance = to_goal.norm();
  if (distance < kEps) return Eigen::Vector2d::Zero();
  Eigen::Vector2d dir = to_goal / distance;
  if (!goal_field_.empty() && goal_field_.goal() == goal) {
    const double h = 0.1;  // steepest descent of the geodesic distance by central differences
    const Eigen::Vector2d g(goal_field_.Distance(x + Eigen::Vector2d(h, 0)) -
                                goal_field_.Distance(x - Eigen::Vector2d(h, 0)),
                            goal_field_.Distance(x + Eigen::Vector2d(0, h)) -
                                goal_field_.Distance(x - Eigen::Vector2d(0, h)));
    if (g.norm() > kEps) dir = -g.normalized();
  }
  return std::min(options_.limits.v_max, distance / 1.0) * dir;  // slows within 1 s of the goal
}

Control OrcaController::Follow(const UnicycleState& robot, const Eigen::Vector2d& velocity) const {
  const double speed = velocity.norm();
  if (!(speed > 1e-6)) return {0.0, 0.0};
  const double error = WrapToPi(std::atan2(velocity.y(), velocity.x()) - robot.heading);
  double v = speed * std::cos(error), turn = error;
  if (v < 0) {
    // Reverse only when standing still is not allowed by some half-plane.
    bool must_move = false;
    for (const OrcaHalfPlane& h : ws_.planes)
      must_move = must_move || h.Margin(Eigen::Vector2d::Zero()) < -1e-6;
    if (must_move)
      turn = WrapToPi(error - M_PI);  // drive backwards, turning the back toward `velocity`
    else
      v = 0;
  }
  const ControlLimits& l = options_.limits;
  return {std::clamp(v, l.v_min, l.v_max),
          std::clamp(options_.heading_gain * turn, -l.omega_max, l.omega_max)};
}

ControlOutcome OrcaController::Compute(const NavigationInput& input) {
  ControlOutcome out;
  try {
    Prepare(input.goal);
    const Eigen::Vector2d x = input.robot.position();
    const int n =
        input.past_rows ? CleanObservations(*input.past_rows, &clean_rows_, &current_) : 0;
    const Eigen::Index p = n > 0 ? clean_rows_.cols() / 2 : 0;
    neighbours_.resize(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) {
      OrcaNeighbour& nb = neighbours_[static_cast<std::size_t>(k)];
      nb.position = current_.col(k);
      nb.velocity.setZero();
      if (p >= 2 && input.observation_step > 0)
        nb.velocity =
            (clean_rows_.row(k).segment(2 * p - 2, 2) - clean_rows_.row(k).segment(2 * p - 4, 2))
                .transpose() /
            input.observation_step;
      nb.radius = options_.pedestrian_radius + options_.safety_margin;
      nb.responsibility = options_.responsibility;
    }
    const Eigen::Vector2d own =
        previous_.v * Eigen::Vector2d(std::cos(input.robot.heading), std::sin(input.robot.heading));
    OrcaOptions o;
    o.time_horizon = options_.time_horizon;
    o.max_speed = options_.limits.v_max;
    o.dt = options_.dt;
    const Eigen::Vector2d preferred = PreferredVelocity(x, input.goal);
    last_ = OrcaVelocity(x, own, options_.robot_radius, preferred, neighbours_, o, &ws_);
    Control u = Follow(input.robot, last_.velocity);
    if (field_) {
      const double now = field_->Value(x.x(), x.y(), &map_ws_);
      auto enters = [&](const Control& c) {
        const UnicycleState s = EulerStep(input.robot, c, options_.dt);
        const double value = field_->Value(s.x, s.y, &map_ws_);
        return now > options_.epsilon ? value > now : value > options_.epsilon;
      };
      for (int k = 0; k < 5 && u.v != 0 && enters(u); ++k) u.v = k < 4 ? 0.5 * u.v : 0.0;
    }
    u = options_.limits.Clamp(u);
    previous_ = u;
    out.command = u;
    out.cost = (last_.velocity - preferred).norm();
    out.evaluations = n;  // tau stays NaN: ORCA has no time-to-collision of a planned control
  } catch (const std::exception& e) {
    out = ControlOutcome::Stop(ControlStatus::kError, e.what());
    previous_ = out.command;
  }
  return out;
}

}  // namespace foresight::nav
