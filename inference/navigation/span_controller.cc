#include "inference/navigation/span_controller.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <nlopt.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/geometry2d.h"

namespace foresight::nav {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// One-control starts of the per-cycle COBYLA runs: a goal-directed turn, a fan, then
/// quasi-random points of the control box (a fixed Halton sequence) up to `initialisations`.
std::vector<Control> Starts(const SpanControllerOptions& o, const UnicycleState& robot,
                            const Eigen::Vector2d& goal) {
  std::vector<Control> s;
  const double bearing = std::atan2(goal.y() - robot.y, goal.x() - robot.x);
  const double turn =
      std::clamp(WrapToPi(bearing - robot.heading) / std::max(o.horizon * 0.5, o.dt),
                 -o.limits.omega_max, o.limits.omega_max);
  s.push_back({o.limits.v_max, turn});
  for (double v : {o.limits.v_max, 0.5 * o.limits.v_max})
    for (double w : {0.0, -0.5, 0.5, -1.0, 1.0}) s.push_back({v, w * o.limits.omega_max});
  s.push_back({0.5 * o.limits.v_min, 0.0});
  s.push_back({0.0, turn});
  auto halton = [](int i, int base) {
    double f = 1.0, r = 0.0;
    for (; i > 0; i /= base) r += (f /= base) * (i % base);
    return r;
  };
  for (int i = 1; static_cast<int>(s.size()) < o.initialisations; ++i)
    s.push_back({o.limits.v_min + (o.limits.v_max - o.limits.v_min) * halton(i, 2),
                 o.limits.omega_max * (2.0 * halton(i, 3) - 1.0)});
  return s;
}

/// The optimisation problem over S constant controls: x = (v_1, omega_1, ..., v_S, omega_S).
struct SegmentProblem {
  std::function<double(const std::vector<Control>&)> cost;
  std::vector<Control> u;  // scratch
  int evaluations = 0;
};

double NloptSegmentCost(unsigned n, const double* x, double*, void* data) {
  auto* p = static_cast<SegmentProblem*>(data);
  ++p->evaluations;
  p->u.resize(n / 2);
  for (unsigned i = 0; i < n / 2; ++i) p->u[i] = {x[2 * i], x[2 * i + 1]};
  return p->cost(p->u);
}

/// COBYLA over `s` constant controls from at most o.initialisations starts: the previous solution
/// (the plan in progress: one cycle of dt has passed, far less than a segment), then every
/// one-control start held over the horizon. Returns the best controls and their cost (inf when
/// no start reached a finite one). Never throws.
std::pair<std::vector<Control>, double> MinimiseFromStarts(
    const SpanControllerOptions& o, int s, const std::vector<Control>& single_starts,
    const std::vector<Control>* previous, double lower_bound, SegmentProblem* problem) {
  std::vector<std::vector<Control>> starts;
  if (previous && static_cast<int>(previous->size()) == s) starts.push_back(*previous);
  for (const Control& c : single_starts) starts.emplace_back(static_cast<std::size_t>(s), c);
  nlopt::opt opt(nlopt::LN_COBYLA, static_cast<unsigned>(2 * s));
  std::vector<double> lower, upper;
  for (int i = 0; i < s; ++i) {
    lower.insert(lower.end(), {o.limits.v_min, -o.limits.omega_max});
    upper.insert(upper.end(), {o.limits.v_max, o.limits.omega_max});
  }
  opt.set_lower_bounds(lower);
  opt.set_upper_bounds(upper);
  opt.set_min_objective(NloptSegmentCost, problem);
  opt.set_maxeval(o.max_evaluations * s);
  opt.set_xtol_abs(o.xtol);
  opt.set_initial_step(o.initial_step);
  std::vector<Control> best(static_cast<std::size_t>(s), Control{0.0, 0.0});
  double best_cost = kInf;
  const int n = std::min<int>(o.initialisations, static_cast<int>(starts.size()));
  std::vector<double> x(static_cast<std::size_t>(2 * s));
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < s; ++k) {
      const Control c =
          o.limits.Clamp(starts[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)]);
      x[static_cast<std::size_t>(2 * k)] = c.v;
      x[static_cast<std::size_t>(2 * k + 1)] = c.omega;
    }
    double f = kInf;
    try {
      opt.optimize(x, f);
    } catch (const std::exception&) {
      // nlopt reports round-off limits and similar by exception; x holds the last iterate.
      f = NloptSegmentCost(static_cast<unsigned>(x.size()), x.data(), nullptr, problem);
    }
    if (std::isfinite(f) && f < best_cost) {
      best_cost = f;
      for (int k = 0; k < s; ++k)
        best[static_cast<std::size_t>(k)] = o.limits.Clamp(
            {x[static_cast<std::size_t>(2 * k)], x[static_cast<std::size_t>(2 * k + 1)]});
    }
    if (best_cost <= lower_bound + 1e-3) break;  // cannot do better than the unobstructed optimum
  }
  return {best, best_cost};
}

/// (Re)builds the goal-distance field when the goal changed (geodesic goal term with a static map).
void UpdateGoalField(const SpanControllerOptions& o, const StaticCollisionField* field,
                     const Eigen::Vector2d& goal, GoalDistanceField* goal_field) {
  if (o.geodesic_goal && field && (goal_field->empty() || goal_field->goal() != goal))
    *goal_field = GoalDistanceField(*field, goal, o.epsilon);
}

}  // namespace

std::string SpanControllerOptions::Problems() const {
  std::ostringstream e;
  if (!(kappa >= 0) || !std::isfinite(kappa)) e << "kappa = " << kappa << " must be >= 0; ";
  if (!(epsilon > 0 && epsilon < 1)) e << "epsilon = " << epsilon << " must be in (0, 1); ";
  if (!(dt > 0) || !std::isfinite(dt)) e << "dt = " << dt << " must be > 0; ";
  if (!(horizon >= dt) || !std::isfinite(horizon))
    e << "horizon = " << horizon << " must be >= dt; ";
  if (!(robot_radius > 0) || !(pedestrian_radius >= 0)) e << "radii must be positive; ";
  if (!(limits.v_min <= 0 && limits.v_max > 0 && limits.omega_max > 0))
    e << "control limits need v_min <= 0 < v_max and omega_max > 0; ";
  if (initialisations < 1) e << "initialisations = " << initialisations << " must be >= 1; ";
  if (segments < 1 || segments > 8) e << "segments = " << segments << " must be in [1, 8]; ";
  if (dt > 0 && segments > std::lround(horizon / dt))
    e << "segments = " << segments << " exceeds the horizon's " << std::lround(horizon / dt)
      << " steps; ";
  if (!(escape_tau >= 0) || !std::isfinite(escape_tau))
    e << "escape_tau = " << escape_tau << " must be >= 0; ";
  if (!(commit_time >= 0) || !std::isfinite(commit_time) ||
      (commit_time > 0 && !(commit_time >= dt && commit_time <= horizon)))
    e << "commit_time = " << commit_time << " must be 0 (off) or in [dt, horizon]; ";
  if (escape_tau > 0 && !(escape_horizon >= dt && escape_horizon <= horizon))
    e << "escape_horizon = " << escape_horizon << " must be in [dt, horizon]; ";
  if (max_evaluations < 3) e << "max_evaluations = " << max_evaluations << " must be >= 3; ";
  return e.str();
}

int CleanObservations(const Eigen::MatrixXd& past_rows, Eigen::MatrixXd* clean,
                      Eigen::Matrix2Xd* current) {
  const Eigen::Index p = past_rows.cols() / 2;
  clean->resize(past_rows.rows(), past_rows.cols());
  current->resize(2, past_rows.rows());
  int kept = 0;
  for (Eigen::Index n = 0; n < past_rows.rows(); ++n) {
    Eigen::Index last = -1;
    for (Eigen::Index i = p - 1; i >= 0 && last < 0; --i)
      if (std::isfinite(past_rows(n, 2 * i)) && std::isfinite(past_rows(n, 2 * i + 1))) last = i;
    if (last < 0) continue;
    const bool all_finite = past_rows.row(n).allFinite();
    for (Eigen::Index i = 0; i < p; ++i) {
      clean->coeffRef(kept, 2 * i) = all_finite ? past_rows(n, 2 * i) : past_rows(n, 2 * last);
      clean->coeffRef(kept, 2 * i + 1) =
          all_finite ? past_rows(n, 2 * i + 1) : past_rows(n, 2 * last + 1);
    }
    current->col(kept) = Eigen::Vector2d(past_rows(n, 2 * last), past_rows(n, 2 * last + 1));
    ++kept;
  }
  return kept;
}

// ---- SPAN -------------------------------------------------------------------------------------

SpanController::SpanController(const span::Predictor* predictor, const StaticCollisionField* field,
                               SpanControllerOptions options)
    : predictor_(predictor), field_(field), options_(std::move(options)), threshold_(0.5) {
  const std::string problems = options_.Problems();
  FS_THROW_UNLESS(problems.empty(), "SPAN controller options: ", problems);
  threshold_ = ChanceThreshold(options_.epsilon);
  steps_ = static_cast<int>(std::lround(options_.horizon / options_.dt));
  escape_steps_ =
      std::clamp(static_cast<int>(std::lround(options_.escape_horizon / options_.dt)), 1, steps_);
  if (field_ && field_->empty()) field_ = nullptr;
  if (field_) map_ws_ = field_->MakeWorkspace();
  if (predictor_) {
    predictor_ws_ = predictor_->MakeWorkspace();
    forecast_.Reserve(64, steps_, predictor_->layout().components);
  }
  forecast_.set_commit_steps(options_.commit_time > 0
                                 ? static_cast<int>(std::lround(options_.commit_time / options_.dt))
                                 : 0);
}

void SpanController::Prepare(const Eigen::Vector2d& goal) {
  UpdateGoalField(options_, field_, goal, &goal_field_);
}

void SpanController::Forecast(const NavigationInput& input) {
  const int n = input.past_rows ? CleanObservations(*input.past_rows, &clean_rows_, &current_) : 0;
  if (predictor_ == nullptr || n == 0) {
    forecast_.FromCurrentPositions(current_.leftCols(n), steps_);
    return;
  }
  FS_THROW_UNLESS(clean_rows_.cols() == 2 * predictor_->observed(),
                  "SPAN controller: observations hold ", clean_rows_.cols() / 2,
                  " points per pedestrian, the predictor expects ", predictor_->observed());
  while (predictions_.size() < static_cast<std::size_t>(n))
    predictions_.push_back(predictor_->MakeDistribution());
  predictor_->PredictBatch(clean_rows_.topRows(n), &predictor_ws_, &predictions_);
  forecast_.FromPredictions(predictions_, n, steps_, options_.dt);
}

double SpanController::Cost(const UnicycleState& robot, const Eigen::Vector2d& goal,
                            const Control& u, double* tau) const {
  return SegmentCost(robot, goal, &u, 1, tau);
}

double SpanController::Cost(const UnicycleState& robot, const Eigen::Vector2d& goal,
                            const std::vector<Control>& u, double* tau) const {
  FS_THROW_UNLESS(!u.empty(), "SPAN controller: Cost() of an empty control sequence");
  return SegmentCost(robot, goal, u.data(), static_cast<int>(u.size()), tau);
}

double SpanController::SegmentCost(const UnicycleState& robot, const Eigen::Vector2d& goal,
                                   const Control* u, int parts, double* tau) const {
  const double r = options_.robot_radius + options_.pedestrian_radius;
  UnicycleState s = robot;
  double t_collide = kInf;
  for (int k = 1; k <= steps_; ++k) {
    // Step k (ending at k dt) uses the segment its start (k - 1) dt falls in.
    s = EulerStep(s, u[std::min(parts - 1, (k - 1) * parts / steps_)], options_.dt);
    if (t_collide < kInf) continue;
    const Eigen::Vector2d p = s.position();
    if ((field_ && field_->Collides(p.x(), p.y(), options_.epsilon, &map_ws_)) ||
        forecast_.Collides(std::min(k, forecast_.steps()), p, r, threshold_))
      t_collide = k * options_.dt;
  }
  if (tau) *tau = t_collide;
  const double distance = GoalDistance(s.position(), goal);
  return std::isfinite(t_collide) ? distance + options_.kappa / t_collide : distance;
}

double SpanController::GoalDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& goal) const {
  return !goal_field_.empty() && goal_field_.goal() == goal ? goal_field_.Distance(p)
                                                            : (p - goal).norm();
}

double SpanController::EscapeCost(const UnicycleState& robot, const Eigen::Vector2d& goal,
                                  const Control& u) const {
  // Why: tau is the first step whose chance bound exceeds epsilon, so it is piecewise constant in
  // u; when every control collides at the first step, kappa / tau is the same for all of them and
  // says nothing about which way is safer. E[#pedestrians in contact at step k] = sum_n P_n(x_k)
  // <= sum_n bound_n(x_k) (eq. upperbounds per pedestrian, linearity of expectation), which does
  // fall as the robot moves away; its mean over the escape window is minimised instead.
  const double r = options_.robot_radius + options_.pedestrian_radius;
  UnicycleState s = robot;
  double contacts = 0.0;
  for (int k = 1; k <= escape_steps_; ++k) {
    s = EulerStep(s, u, options_.dt);
    const Eigen::Vector2d p = s.position();
    if (field_ && field_->Collides(p.x(), p.y(), options_.epsilon, &map_ws_)) contacts += 1.0;
    contacts += forecast_.UnionBound(std::min(k, forecast_.steps()), p, r);
  }
  const double distance = GoalDistance(s.position(), goal);
  return contacts / escape_steps_ + 1e-3 * distance;
}

ControlOutcome SpanController::Compute(const NavigationInput& input) {
  ControlOutcome out;
  try {
    Forecast(input);
    Prepare(input.goal);
    SegmentProblem problem;
    problem.cost = [&](const std::vector<Control>& u) {
      return Cost(input.robot, input.goal, u, nullptr);
    };
    const double here = GoalDistance(input.robot.position(), input.goal);
    // The weighted geodesic distance can drop faster than v_max near walls (up to 1 +
    // margin_weight).
    const double rate = goal_field_.empty() ? 1.0 : 1.0 + goal_field_.margin_weight();
    const double lower = std::max(0.0, here - rate * options_.limits.v_max * options_.horizon);
    auto [best, cost] =
        MinimiseFromStarts(options_, options_.segments, Starts(options_, input.robot, input.goal),
                           previous_.empty() ? nullptr : &previous_, lower, &problem);
    out.evaluations = problem.evaluations;
    if (!std::isfinite(cost)) {
      out.status = ControlStatus::kNoFinitePlan;
      out.message = "no start of the optimiser reached a finite cost";
      out.command = {0, 0};
      previous_.clear();
      return out;
    }
    out.command = best.front();
    out.cost = Cost(input.robot, input.goal, best, &out.tau);
    if (options_.escape_tau > 0 && out.tau <= options_.escape_tau + 1e-9) {
      SegmentProblem escape;
      escape.cost = [&](const std::vector<Control>& u) {
        return EscapeCost(input.robot, input.goal, u.front());
      };
      // E >= 1e-3 x the goal distance after the window, which cannot drop by more than
      // rate v_max escape_horizon: a start reaching that is optimal.
      const double escape_lower =
          1e-3 * std::max(0.0, here - rate * options_.limits.v_max * options_.escape_horizon);
      const auto [controls, escape_cost] = MinimiseFromStarts(
          options_, 1, Starts(options_, input.robot, input.goal), nullptr, escape_lower, &escape);
      out.evaluations += escape.evaluations;
      if (std::isfinite(escape_cost)) {
        ++escapes_;
        out.fallback = true;
        best.assign(static_cast<std::size_t>(options_.segments), controls.front());
        out.command = controls.front();
        out.cost = Cost(input.robot, input.goal, best, &out.tau);
      }
    }
    previous_ = std::move(best);
  } catch (const std::exception& e) {
    out = ControlOutcome::Stop(ControlStatus::kError, e.what());  // e.g. malformed observations
    previous_.clear();
  }
  return out;
}

// ---- reactive ---------------------------------------------------------------------------------

ReactiveController::ReactiveController(const StaticCollisionField* field,
                                       SpanControllerOptions options, double heading_weight)
    : field_(field),
      options_(std::move(options)),
      heading_weight_(heading_weight),
      threshold_(0.5) {
  const std::string problems = options_.Problems();
  FS_THROW_UNLESS(problems.empty(), "reactive controller options: ", problems);
  threshold_ = ChanceThreshold(options_.epsilon);
  if (field_ && field_->empty()) field_ = nullptr;
  if (field_) map_ws_ = field_->MakeWorkspace();
}

double ReactiveController::Cost(const UnicycleState& robot, const Eigen::Vector2d& goal,
                                const Control& u, bool* collides) const {
  const UnicycleState s = EulerStep(robot, u, options_.dt);
  const Eigen::Vector2d p = s.position();
  const bool hit =
      (field_ && field_->Collides(p.x(), p.y(), options_.epsilon, &map_ws_)) ||
      forecast_.Collides(1, p, options_.robot_radius + options_.pedestrian_radius, threshold_);
  if (collides) *collides = hit;
  double bearing = std::atan2(goal.y() - p.y(), goal.x() - p.x());
  double distance = (p - goal).norm();
  if (!goal_field_.empty() && goal_field_.goal() == goal) {
    distance = goal_field_.Distance(p);
    const double h = 0.1;  // steepest descent of the geodesic distance by central differences
    const double gx = goal_field_.Distance(p + Eigen::Vector2d(h, 0)) -
                      goal_field_.Distance(p - Eigen::Vector2d(h, 0));
    const double gy = goal_field_.Distance(p + Eigen::Vector2d(0, h)) -
                      goal_field_.Distance(p - Eigen::Vector2d(0, h));
    if (std::hypot(gx, gy) > 1e-9) bearing = std::atan2(-gy, -gx);
  }
  return distance + heading_weight_ * std::abs(WrapToPi(bearing - s.heading)) +
         (hit ? options_.kappa : 0.0);
}

void ReactiveController::Prepare(const Eigen::Vector2d& goal) {
  UpdateGoalField(options_, field_, goal, &goal_field_);
}

ControlOutcome ReactiveController::Compute(const NavigationInput& input) {
  ControlOutcome out;
  try {
    Eigen::MatrixXd clean;
    const int n = input.past_rows ? CleanObservations(*input.past_rows, &clean, &current_) : 0;
    forecast_.FromCurrentPositions(current_.leftCols(n), 1);
    Prepare(input.goal);
    SegmentProblem problem;
    problem.cost = [&](const std::vector<Control>& u) {
      return Cost(input.robot, input.goal, u.front(), nullptr);
    };
    const auto [controls, cost] = MinimiseFromStarts(
        options_, 1, Starts(options_, input.robot, input.goal), nullptr, 0.0, &problem);
    const Control best = controls.front();
    out.evaluations = problem.evaluations;
    bool hit = true;
    if (std::isfinite(cost)) Cost(input.robot, input.goal, best, &hit);
    if (hit) {
      out.status = ControlStatus::kNoFinitePlan;
      out.message = "every candidate control collides";
      out.command = {0, 0};
      return out;
    }
    out.command = best;
    out.cost = cost;
    // tau stays NaN: the reactive controller plans one step, no time-to-collision to report
  } catch (const std::exception& e) {
    out = ControlOutcome::Stop(ControlStatus::kError, e.what());
  }
  return out;
}

}  // namespace foresight::nav
