#pragma once
/// SPAN: stochastic process anticipatory navigation (thesis ch 5, eqs. costOpt-costOptc, Algorithm
/// 1). Each cycle: predict every observed pedestrian's future as a stochastic process with the SPAN
/// engine, then minimise over constant controls u = (v, omega) on the horizon T
///   J(u) = ||x(T) - g|| + kappa / tau(x_0, u, o, f_m)
/// with COBYLA (NLopt) from several initialisations. tau is the first Euler step k dt at which the
/// erf bound on the collision probability with any pedestrian exceeds epsilon (eq. dynamicCheck)
/// or the swept occupancy of the static map exceeds epsilon (eq. staticCheck); without collision
/// on the horizon tau = inf and the TTC term vanishes.
///
/// The same class with `anticipate = false` and a one-step horizon is the reactive baseline.

#include <memory>
#include <vector>

#include "inference/navigation/controller.h"
#include "inference/navigation/crowd_forecast.h"
#include "inference/navigation/goal_distance.h"
#include "inference/navigation/static_clearance.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::nav {

struct SpanControllerOptions {
  double kappa = 100.0;            ///< weight of the inverse time-to-collision
  double epsilon = 0.25;           ///< chance threshold
  double horizon = 4.0;            ///< T (s)
  double dt = 0.1;                 ///< Euler step of the rollout (s)
  double robot_radius = 0.4;       ///< m
  double pedestrian_radius = 0.4;  ///< m
  ControlLimits limits;
  int initialisations = 12;   ///< COBYLA starts per cycle (the previous solution first)
  int max_evaluations = 40;   ///< per start
  double xtol = 1e-3;         ///< COBYLA tolerance on u
  double initial_step = 0.4;  ///< COBYLA initial trust radius on u
  /// Constant controls per horizon: 1 is the thesis's one constant control (v, omega) over T;
  /// 2 lets it change once, at T / 2 (u is then 4-dimensional; the robot executes the first).
  int segments = 1;
  /// Fallback when nothing better than an imminent collision is found: when the chosen plan's
  /// time-to-collision (pedestrians or the static map) is at most `escape_tau` (s), the command
  /// instead minimises EscapeCost over the next `escape_horizon` s. 0 turns it off (the thesis:
  /// the kappa / tau term is then the same for every control and the goal term alone decides,
  /// driving on through the pedestrian). escape_horizon is checked (in [dt, horizon]) only when
  /// the fallback is on.
  double escape_tau = 0.0;
  double escape_horizon = 1.0;  ///< s, at least dt and at most the horizon
  /// Commitment time t_c (s; 0 = off, the thesis): the collision test at t_k > t_c uses the
  /// predicted mean at t_k with the covariance at t_c. Why: the robot re-plans every dt, so a
  /// predicted contact at t_k only commits it if it must still be avoided when its last chance
  /// to react comes, about t_c before. If forecasts are updated without bias (each newer forecast
  /// of o(t_k) is the current one plus zero-mean news; exact for a random walk), the forecast
  /// made at t_k - t_c has its mean spread around today's with a' (Sigma_k - Sigma_c) a and keeps
  /// residual variance a' Sigma_c a. That later plan flags the step when a'd' < r + c sqrt(2 a'
  /// Sigma_c a), which happens with probability above 1/2 exactly when today's mean offset d
  /// satisfies the same inequality: the thesis's test with Sigma_c in place of Sigma_k. Per step
  /// this is epsilon_k = erfc(c sqrt(a' Sigma_c a / a' Sigma_k a)) / 2 >= epsilon. Mixture
  /// forecasts hold each component's covariance the same way (a heuristic extension). t_c about
  /// dt + (r_robot + r_ped) / |v_min| (time to back out of contact). EscapeCost keeps the full
  /// covariance.
  double commit_time = 0.0;
  /// With a static map: measure the goal term as the geodesic distance around obstacles
  /// (GoalDistanceField) instead of ||x(T) - g||; identical where the way to the goal is free.
  bool geodesic_goal = true;
  /// Describe problems (names the offending field) or return an empty string.
  std::string Problems() const;
};

class SpanController final : public NavigationController {
 public:
  /// @param predictor SPAN engine (null: no pedestrian prediction; pedestrians stand still).
  /// @param field swept static map (null or empty: no static obstacles). Both must outlive the
  /// controller.
  SpanController(const span::Predictor* predictor, const StaticCollisionField* field,
                 SpanControllerOptions options);
  std::string name() const override { return "span"; }
  void Prepare(const Eigen::Vector2d& goal) override;
  ControlOutcome Compute(const NavigationInput& input) override;

  /// J(u) from `robot` towards `goal` against the current forecast; `tau` receives the TTC (inf:
  /// none). One control held over the horizon.
  double Cost(const UnicycleState& robot, const Eigen::Vector2d& goal, const Control& u,
              double* tau) const;
  /// Same for piecewise-constant controls: u[i] held over the i-th of u.size() equal parts of the
  /// horizon (options().segments of them in Compute).
  double Cost(const UnicycleState& robot, const Eigen::Vector2d& goal,
              const std::vector<Control>& u, double* tau) const;
  /// The escape objective for one control held from `robot`: over the steps k = 1..K of
  /// escape_horizon, the mean of the union bound sum_n bound_n(x_k) (CrowdForecast::UnionBound,
  /// an upper bound on the expected number of pedestrians in contact) plus 1 for a step in the
  /// static map's collision region (swept occupancy above epsilon: a penalty, not a bound), plus
  /// 1e-3 times the goal distance at step K (ties go towards the goal).
  double EscapeCost(const UnicycleState& robot, const Eigen::Vector2d& goal,
                    const Control& u) const;
  /// Fills the forecast from observations (done by Compute; exposed for tests and drawing).
  void Forecast(const NavigationInput& input);
  const CrowdForecast& forecast() const { return forecast_; }
  /// Predictions of the last cycle (first forecast().pedestrians() entries are valid).
  const std::vector<TrajectoryDistribution>& predictions() const { return predictions_; }
  const std::vector<TrajectoryDistribution>* Predictions() const override { return &predictions_; }
  int PredictedPedestrians() const override { return forecast_.pedestrians(); }
  const SpanControllerOptions& options() const { return options_; }
  int steps() const { return steps_; }
  /// Cycles whose command came from the escape fallback, since construction.
  int escapes() const { return escapes_; }

 private:
  /// The goal term's distance: geodesic when the field is built for `goal`, else Euclidean.
  double GoalDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& goal) const;
  double SegmentCost(const UnicycleState& robot, const Eigen::Vector2d& goal, const Control* u,
                     int parts, double* tau) const;

  const span::Predictor* predictor_;
  const StaticCollisionField* field_;
  SpanControllerOptions options_;
  ChanceThreshold threshold_;
  int steps_;
  int escape_steps_;
  int escapes_ = 0;
  CrowdForecast forecast_;
  std::vector<TrajectoryDistribution> predictions_;
  span::Predictor::Workspace predictor_ws_;
  mutable occupancy::MapWorkspace map_ws_;
  Eigen::MatrixXd clean_rows_;
  Eigen::Matrix2Xd current_;
  std::vector<Control> previous_;  ///< last cycle's solution (segments), empty: none
  GoalDistanceField goal_field_;   ///< rebuilt when the goal changes
};

/// The reactive baseline (thesis ch 5, "Experimental Evaluation"): optimises the next step only,
/// without anticipation. Pedestrians are taken at their current positions; the cost is the distance
/// to the goal after one step plus `heading_weight` times the heading error to the direction of
/// travel, with kappa added when the step collides (pedestrian discs or the swept static map).
/// Stops when every candidate collides. With a static map the distance and the direction of
/// travel come from the same geodesic GoalDistanceField as SPAN's (same map knowledge; the
/// baselines differ only in anticipation).
class ReactiveController final : public NavigationController {
 public:
  ReactiveController(const StaticCollisionField* field, SpanControllerOptions options,
                     double heading_weight = 0.5);
  std::string name() const override { return "reactive"; }
  void Prepare(const Eigen::Vector2d& goal) override;
  ControlOutcome Compute(const NavigationInput& input) override;
  double Cost(const UnicycleState& robot, const Eigen::Vector2d& goal, const Control& u,
              bool* collides) const;

 private:
  const StaticCollisionField* field_;
  SpanControllerOptions options_;
  double heading_weight_;
  ChanceThreshold threshold_;
  CrowdForecast forecast_;
  GoalDistanceField goal_field_;
  Eigen::Matrix2Xd current_;
  mutable occupancy::MapWorkspace map_ws_;
};

/// Last finite position of each row of `past_rows` into `current` [2 x n]; rows without any finite
/// point are dropped. @return number of pedestrians kept. Rows with some non-finite points are
/// rewritten in `clean` as a pedestrian standing at its last finite point.
int CleanObservations(const Eigen::MatrixXd& past_rows, Eigen::MatrixXd* clean,
                      Eigen::Matrix2Xd* current);

}  // namespace foresight::nav
