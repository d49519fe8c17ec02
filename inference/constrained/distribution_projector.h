#pragma once
/// The runtime projector of structurally constrained prediction (thesis ch 7, eq.
/// formulationWhole): a predicted mixture of matrix normals (the SPAN predictor's
/// TrajectoryDistribution) is made collision-compliant component by component, the mixture weights
/// fixed as in the thesis:
///   min_theta_r KL(p_theta_r || p_prior_r)  s.t.  C_r(p_theta_r) <= epsilon - margin,
/// for every component with C_r > epsilon - margin (kl.h, collision_cost.h, projection.h). As
/// C = sum_r alpha_r C_r with sum_r alpha_r = 1, the mixture then meets C <= epsilon; the returned
/// C is recomputed on the result, never taken from the solver. The position mean of a prediction
/// is origin + v t + M' phi(t) (span_predictor.h): the projector passes origin + v t_k to the cost
/// as a constant offset. The optimiser's parametrisation needs a diagonal U (u_param: diagonal).
///
///   DistributionProjector projector(&map, model.basis(), times, ProjectorOptions{});
///   auto ws = projector.MakeWorkspace();                     // one per caller
///   TrajectoryDistribution out = prior;                       // sized once
///   TrackProjection r = projector.Project(prior, &out, &ws);  // never throws on solver failure

#include <Eigen/Core>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "core/rbf.h"
#include "inference/constrained/collision_cost.h"
#include "inference/constrained/component.h"
#include "inference/constrained/projection.h"
#include "inference/mapping/occupancy_map.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::constrained {

/// ComponentParams of component r of `d` (M, log_u_i = 2 log L_U(i,i), L_V). Error naming
/// "u_param: diagonal" when L_U has a non-zero off-diagonal entry, and when r is out of range.
ComponentParams ToComponentParams(const TrajectoryDistribution& d, int r);
/// The inverse: writes M, L_U = diag(exp(log_u / 2)) and L_V into component r of *d. Error when a
/// shape differs from d's.
void SetFromComponentParams(const ComponentParams& p, int r, TrajectoryDistribution* d);

struct ProjectorOptions {
  double epsilon = 0.05;     ///< C <= epsilon is compliant (thesis 0.05), in (0, 1)
  double margin = 2e-4;      ///< solve to epsilon - margin so the returned C is truly <= epsilon
  int order = 6;             ///< Gauss-Hermite points per axis
  ProjectionOptions solver;  ///< its epsilon is overwritten with epsilon - margin
  /// Verification by a second, more accurate operator (0: off): Gauss-Hermite order `check_order`
  /// on the constructor's `check_times`. The solver drives the configured operator down and so
  /// seeks out its quadrature error (mass between the nodes); when the check operator finds the
  /// result above epsilon - check_slack, the solve is repeated, warm-started at the last solution:
  /// when the configured operator had solved every component, first with it again and its target
  /// lowered by the excess (C_check - (epsilon - margin)), cheap and enough for a small gap; then
  /// against the check operator itself (every component it finds above epsilon - margin); then
  /// against it with the target lowered by the excess it left: at most `check_rounds` repeated
  /// solves, stopping early once a solve against the check operator ends without a compliant point
  /// (a repeated solve that fails outright keeps the last result, infeasible). The check operator's
  /// verdict is the result's (`feasible`, `status`).
  int check_order = 0;
  int check_rounds = 3;
  /// The check accepts C_check <= epsilon - check_slack (the check operator's own error bound, so
  /// that the true C meets epsilon); 0, or in (0, margin).
  double check_slack = 0;
};

/// Outcome of one track's projection (expected outcomes are values here, never exceptions).
struct TrackProjection {
  bool changed = false;   ///< false: the prior's mixture C already met epsilon (returned unchanged)
  bool feasible = false;  ///< mixture C of the result <= epsilon (with a check: the checked C)
  double prior_cost = 0, cost = 0;  ///< mixture C before / after (the configured operator)
  // `components`, `kl` and `evaluations` (summed over every solve) describe the last solve, which
  // may have been against the check operator.
  double checked_cost = NAN;  ///< C of the result under the check operator (NaN: no check)
  int check_rounds = 0;       ///< repeated solves the check asked for
  double kl = 0;              ///< sum_r alpha_r KL_r
  double seconds = 0;         ///< wall time of Project (steady_clock)
  int evaluations = 0;        ///< objective evaluations over components
  /// Per component: kAlreadyFeasible when C_r <= epsilon - margin or when the mixture already met
  /// epsilon (nothing projected), else the solver's outcome.
  std::vector<ProjectionSummary> components;
  /// "compliant_prior" | "solved" | "infeasible" | "failed": the worst outcome over components
  /// (with a check operator: its verdict on the result, so "infeasible" may come with every
  /// component solved under the configured operator), and never "solved" or "compliant_prior"
  /// unless `feasible`.
  std::string status;
};

/// Projects predicted mixtures onto {C <= epsilon} per component (see the file comment).
/// Immutable after construction; one Workspace per caller.
class DistributionProjector {
 public:
  struct Workspace {
    CollisionCost::Workspace cost;   ///< its offset holds origin + v t_k of the current track
    CollisionCost::Workspace check;  ///< the same for the check operator (when there is one)
    ComponentGradient gradient;      ///< sized scratch for callers of cost() with a gradient
                                     ///< (Project's solver owns its own)
    ComponentParams component;       ///< scratch: one component in the optimiser's parameters
  };

  /// @param map occupancy map (kept by pointer; must outlive this). @param basis the predictor's
  /// trajectory basis phi(t). @param times the K points of the rectangle rule (s after the last
  /// observation, e.g. dt, 2 dt, ..., f dt). Error naming a bad option (epsilon, margin, order,
  /// solver limits).
  DistributionProjector(const occupancy::Map* map, const TimeBasis& basis, Eigen::VectorXd times,
                        const ProjectorOptions& options);
  /// With a check operator (options.check_order > 0) on `check_times` (error when the order is
  /// out of [1, 64] or check_times is empty). The constructor above refuses check_order != 0.
  DistributionProjector(const occupancy::Map* map, const TimeBasis& basis, Eigen::VectorXd times,
                        const ProjectorOptions& options, Eigen::VectorXd check_times);

  const ProjectorOptions& options() const { return options_; }
  const CollisionCost& cost() const { return cost_; }
  Workspace MakeWorkspace() const;

  /// Mixture C of d (its origin/velocity offset applied). No allocation once `ws` holds a
  /// component of d's basis (MakeWorkspace does not know it: the first call sizes it). Error when
  /// d's basis size differs from the projector's or L_U is not diagonal; NaN when d holds NaN.
  double Cost(const TrajectoryDistribution& d, Workspace* ws) const;

  /// Projects `prior` into *out, which must have prior's shape (components and basis; a copy of
  /// the prior is fine, `out` may be `&prior`). Never throws on solver or numeric failure (the
  /// status says so); Error only for shape or u_param misuse.
  TrackProjection Project(const TrajectoryDistribution& prior, TrajectoryDistribution* out,
                          Workspace* ws) const;

 private:
  /// Writes origin + v t_k of `times` into *offset.
  static void SetOffset(const TrajectoryDistribution& d, const Eigen::VectorXd& times,
                        Eigen::Matrix2Xd* offset);
  /// One projection against operator `op` (cost_ or *check_, with its workspace): nothing when
  /// the prior's mixture C <= mixture_limit, else every component with C_r > target is solved to
  /// target. SLSQP warm-started at `start`'s components when given (the previous solution).
  /// result.cost and result.feasible are judged by the configured operator.
  TrackProjection ProjectOnce(const TrajectoryDistribution& prior, TrajectoryDistribution* out,
                              Workspace* ws, const CollisionCost& op,
                              CollisionCost::Workspace* op_ws, double mixture_limit, double target,
                              const TrajectoryDistribution* start = nullptr) const;
  /// Mixture C of d under the check operator (NaN if it throws or d holds NaN).
  double CheckCost(const TrajectoryDistribution& d, Workspace* ws) const;

  ProjectorOptions options_;
  CollisionCost cost_;
  std::optional<CollisionCost> check_;
};

}  // namespace foresight::constrained
