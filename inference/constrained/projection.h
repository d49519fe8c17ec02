#pragma once
/// The constraint projection of structurally constrained prediction (thesis ch 7, eq.
/// formulationWhole), per component with the mixture weights fixed (as the thesis):
///   min_theta KL(p_theta || p_prior)  s.t.  C(p_theta) - epsilon <= 0,
/// solved by NLopt's SLSQP (NLOPT_LD_SLSQP) from the prior (theta in component.h's flat layout).
/// A component whose prior already satisfies the constraint is returned unchanged (KL 0). Each
/// component meeting C_r <= epsilon makes the mixture meet it (C = sum alpha_r C_r).
/// The runtime path never throws: failures are a status in the summary.

#include <functional>
#include <string>

#include "inference/constrained/component.h"

namespace foresight::constrained {

/// The constraint: its value C(p) and, when `gradient` is not null, its derivatives.
using ConstraintFunction =
    std::function<double(const ComponentParams& p, ComponentGradient* gradient)>;

struct ProjectionOptions {
  double epsilon = 0.05;  ///< allowed cost (thesis: 0.05)
  double tolerance =
      1e-4;  ///< constraint tolerance of the solver; feasibility is C <= epsilon + tolerance
  double xtol_rel = 1e-6;     ///< NLopt relative parameter tolerance
  int max_evaluations = 300;  ///< objective evaluations at most
  double max_seconds = 1.0;   ///< wall-time limit per component (0: none)
  int restarts = 2;  ///< restarts from the lowest-cost point when SLSQP stops without a feasible
                     ///< one (each with max_evaluations)
  /// When those find no feasible point: minimise C alone (L-BFGS, max_evaluations) until it meets
  /// the constraint, then SLSQP from there (not in the thesis; only runs where SLSQP failed).
  bool feasibility_phase = true;
  /// Starts of that phase: this many weight samples of the prior as means, with the variances of
  /// U divided by exp(feasibility_shrink); the lowest-KL feasible one (else the lowest-C one)
  /// starts it. Seeded, so a projection is deterministic.
  int feasibility_samples = 64;
  double feasibility_shrink = 4.0;
  unsigned feasibility_seed = 1;
};

enum class ProjectionStatus {
  kAlreadyFeasible,  ///< the prior met the constraint; returned unchanged
  kSolved,           ///< SLSQP converged to a point that meets the constraint
  kInfeasible,       ///< the solver stopped (any reason) at a point that violates it
  kFailed,           ///< NLopt reported an error, or a value was not finite (the prior is returned)
};
const char* ToString(ProjectionStatus s);

struct ProjectionSummary {
  ProjectionStatus status = ProjectionStatus::kFailed;
  std::string nlopt_result;  ///< NLopt's result code name ("NLOPT_XTOL_REACHED", ...), or ""
  int evaluations = 0;       ///< objective evaluations
  double kl = 0;             ///< KL of the returned component from the prior
  double cost = 0;           ///< constraint value C of the returned component
  double prior_cost = 0;     ///< C of the prior
  double seconds = 0;
  bool feasible() const {
    return status == ProjectionStatus::kAlreadyFeasible || status == ProjectionStatus::kSolved;
  }
};

/// Projects `prior` onto {C <= epsilon}; writes the result into *out (the prior itself unless
/// solved or infeasible-but-improved: on kInfeasible the best point found is returned). Never
/// throws for solver or numeric failures.
ProjectionSummary ProjectComponent(const ComponentParams& prior, const ConstraintFunction& cost,
                                   const ProjectionOptions& options, ComponentParams* out);
/// The same from a warm start `warm_start` (e.g. the solution under a cruder constraint): SLSQP
/// starts there, and the result is never worse than it (it is a candidate like any point visited).
/// The KL is still measured from `prior`; a non-finite or invalid start is ignored (the prior is
/// used). As without a start, a callback that fails (throws, non-finite) returns the prior with
/// kFailed.
ProjectionSummary ProjectComponent(const ComponentParams& prior, const ConstraintFunction& cost,
                                   const ProjectionOptions& options, ComponentParams* out,
                                   const ComponentParams& warm_start);

}  // namespace foresight::constrained
