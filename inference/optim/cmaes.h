#pragma once
/// CMA-ES, the covariance matrix adaptation evolution strategy, as in N. Hansen, "The CMA Evolution
/// Strategy: A Tutorial" (2016, arXiv:1604.00772; "tutorial" below): the algorithm of its Fig. 6,
/// eqs. (38)-(47), with the default parameters of its Table 1, eqs. (48)-(58), positive
/// recombination weights only (no "active" negative weights), the lazy eigendecomposition of App.
/// B.2, the termination criteria of App. B.3 and the flat-fitness escape of App. B.4.
///
/// Departures from the thesis (seeds/thesis.tex ch. 2, "Covariance Matrix Adaptation Evolution
/// Strategy"), which prints the update with typos; this file follows the tutorial:
///   - p_C update: a `+` is missing before the sqrt term; the tutorial's (45) also multiplies that
///     term by the stall indicator h_sigma;
///   - C update: `sum_i x_i` must be `sum_i w_i` (= 1 here), the rank-mu steps are
///     (x_i - m_k) / sigma_k (old mean and step size, tutorial (47)), and the (1 - h_sigma) c_c
///     (2 - c_c) correction term delta(h_sigma) is added;
///   - mu_eff = 1 / sum_i w_i^2 (not 1 / sum_i w_i).
///
/// Interface: ask/tell, so the caller evaluates a batch (in parallel) itself:
///   CmaEs es(mean0, options);
///   while (es.status() == CmaEsStatus::kRunning) {
///     const Eigen::MatrixXd& X = es.Ask();          // [n x lambda], inside the bounds
///     Eigen::VectorXd costs = EvaluateColumns(X);   // caller's code
///     es.Tell(costs);                               // returns the status
///   }
///
/// Box bounds (joint limits): repair by projection plus an adaptive quadratic penalty, Hansen,
/// Niederberger, Guzzella and Koumoutsakos, "A Method for Handling Uncertainty in Evolutionary
/// Optimization ...", IEEE TEC 13(1), 2009, its box-constraint handling (the `BoundPenalty` of
/// Hansen's reference code pycma, cma/boundary_handler.py):
///   - each sample x_k = m + sigma y_k is projected onto the box, x_k^feas; Ask() returns x_k^feas,
///     so the caller only ever evaluates in-bounds points;
///   - the ranking uses f(x_k^feas) + (1/n) sum_i gamma_i (x_k,i - x_k,i^feas)^2, and the
///     update uses the unrepaired step y_k (the projection does not bias the distribution);
///   - gamma_i = 2 delta_fit, delta_fit = median over the last 20 + 3n/lambda generations of the
///     interquartile range of the costs divided by sigma^2 mean_i(C_ii). The weights follow
///     delta_fit until the mean first leaves the box; from then on gamma_i is multiplied by
///     1.1^min(1, mu_eff / (10 n)) in each generation where |m_i - m_i^feas| exceeds
///     3 max(1, sqrt(n) / mu_eff) sigma sqrt(C_ii). (TEC 2009 prints max(1, mu_eff/(10n)); the
///     reference code's version of this rule uses min, noting that max fails on a bounded
///     cigar-tablet; its current default replaces the factor by a smoother tanh-based one.)
///   Consequently mean() may lie slightly outside the box; best_x() never does.
///
/// Injected (externally generated) candidates, e.g. the first batch of GFCS drawn from a learned
/// sampler: Inject(X) before Ask() makes the first columns of the next batch equal to X (projected
/// onto the box; no penalty). For the update their step y = (x - m) / sigma is clipped in
/// Mahalanobis length, y <- y min(1, c_y / ||C^{-1/2} y||), c_y = sqrt(n) + 2n / (n + 2) (N.
/// Hansen, "Injecting External Solutions Into CMA-ES", arXiv:1110.4181, 2011, eq. (4) and its Table
/// 1). Clipped steps then enter (42)-(47) like sampled ones. A warm start therefore is: mean0 = the
/// best warm-start sample (or the sampler's mean), then Inject() the rest of the warm-start samples
/// (at most lambda).
///
/// Expected outcomes are statuses, never exceptions: non-finite costs are ranked last (worst) and
/// counted (non_finite_costs()); a generation with no finite cost stops the run with
/// kNonFiniteCosts (nothing can be ranked). If an update would make m, sigma, the paths or C
/// non-finite, or C not positive definite, the update is discarded (the state stays the last good
/// one, so no NaN reaches the caller) and the run stops with kNumericalError. A condition number of
/// C above options.max_condition (tutorial B.3 "ConditionCov", 1e14) stops with kConditionCov.
/// There are no automatic restarts: a caller that wants IPOP restarts (Auger and Hansen 2005)
/// constructs a new CmaEs with a larger population.
///
/// Bad input (wrong sizes, sigma0 <= 0, lower > upper, mean0 outside the box, Tell before Ask, ...)
/// throws foresight::Error naming the field and value.
///
/// Determinism: std::mt19937_64 seeded with options.seed and std::normal_distribution; the same
/// seed, inputs and standard library give the same run.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace foresight::optim {

/// Why a run stopped (kRunning while it has not).
enum class CmaEsStatus {
  kRunning,
  kTargetReached,   ///< best_cost() <= options.target_cost
  kMaxEvaluations,  ///< another generation would exceed options.max_evaluations
  kTolFun,          ///< tutorial B.3 TolFun: recent best costs and the last batch within tol_fun
  kTolX,            ///< tutorial B.3 TolX: sigma sqrt(C_ii) and sigma p_c,i below tol_x sigma0
  kConditionCov,    ///< tutorial B.3 ConditionCov: cond(C) > options.max_condition
  kNoEffect,        ///< tutorial B.3 NoEffectAxis/NoEffectCoord: steps no longer change the mean
  kNonFiniteCosts,  ///< a whole generation's costs were NaN or +-inf
  kNumericalError,  ///< the update became non-finite or C lost positive definiteness
};
const char* ToString(CmaEsStatus status);

/// Options (named, with defaults). Check with IsValid(); the CmaEs constructor throws on invalid.
struct CmaEsOptions {
  /// lambda, candidates per generation; 0 selects the tutorial default 4 + floor(3 ln n), eq. (48).
  /// Otherwise >= 2. mu = floor(lambda / 2) candidates are recombined.
  int population = 0;
  /// Initial step size sigma^(0) (units of the decision vector). Problem dependent: the optimum
  /// should lie within mean0 +- 2 sigma0 in each coordinate; about a quarter to a half of the box
  /// width. Default 0.3 as in the tutorial's App. C code.
  double sigma0 = 0.3;
  /// Seed of the std::mt19937_64 drawing the N(0, I) samples.
  std::uint64_t seed = 1;
  /// Box bounds [n] each, or both empty (unbounded). Entries may be -inf / +inf (one-sided).
  /// lower_i == upper_i fixes coordinate i.
  Eigen::VectorXd lower, upper;
  /// Evaluation budget; a generation that would exceed it is not started. 0 selects 1000 n^2
  /// (the tutorial's App. C code).
  std::int64_t max_evaluations = 0;
  /// Stop when the best cost found is <= target_cost (-inf: never).
  double target_cost = -std::numeric_limits<double>::infinity();
  /// Tutorial B.3 TolFun (absolute, in cost units): stop when the best costs of the last
  /// 10 + ceil(30 n / lambda) generations and all costs of the last generation lie within a range
  /// < tol_fun. 0 disables.
  double tol_fun = 1e-12;
  /// Tutorial B.3 TolX, relative to sigma0: stop when sigma sqrt(C_ii) < tol_x sigma0 and
  /// sigma |p_c,i| < tol_x sigma0 for all i. 0 disables.
  double tol_x = 1e-12;
  /// Tutorial B.3 ConditionCov: stop when the condition number of C exceeds this (> 1).
  double max_condition = 1e14;

  /// True when every field is usable; otherwise false, and `*error` (if not null) names the first
  /// bad field and its value (Ceres style). Sizes against the dimension are checked by CmaEs.
  bool IsValid(std::string* error) const;
};

/// The strategy parameters of the tutorial's Table 1 for dimension n and population lambda.
struct CmaEsParameters {
  int n = 0;
  int lambda = 0;           ///< eq. (48)
  int mu = 0;               ///< floor(lambda / 2)
  Eigen::VectorXd weights;  ///< [mu] w_i = w'_i / sum_j w'_j, w'_i = ln((lambda+1)/2) - ln i, (49)
  double mu_eff = 0;        ///< (sum w_i)^2 / sum w_i^2 = 1 / sum w_i^2
  double c_m = 1;           ///< (54)
  double c_sigma = 0;       ///< (mu_eff + 2) / (n + mu_eff + 5), (55)
  double d_sigma = 0;       ///< 1 + 2 max(0, sqrt((mu_eff - 1)/(n + 1)) - 1) + c_sigma, (55)
  double c_c = 0;           ///< (4 + mu_eff/n) / (n + 4 + 2 mu_eff/n), (56)
  double c_1 = 0;           ///< 2 / ((n + 1.3)^2 + mu_eff), (57) with alpha_cov = 2
  double c_mu = 0;          ///< min(1 - c_1, 2 (mu_eff - 2 + 1/mu_eff) / ((n+2)^2 + mu_eff)), (58)
  double chi_n = 0;         ///< E||N(0, I)|| ~ sqrt(n) (1 - 1/(4n) + 1/(21 n^2))
  double eigen_interval = 0;  ///< decompose C after this many evaluations: lambda/(c_1+c_mu)/n/10
  double c_y = 0;             ///< injection clip sqrt(n) + 2n/(n+2) (Hansen 2011)
};
/// Table 1 for dimension n >= 1 and population lambda >= 2 (0: the default of eq. (48)).
CmaEsParameters MakeCmaEsParameters(int n, int lambda);

/// One CMA-ES run (ask/tell). Not thread safe; the caller parallelises the evaluations.
class CmaEs {
 public:
  /// @param mean0 [n] initial mean m^(0), inside the box when bounds are set.
  /// @param options validated here (throws foresight::Error on bad input).
  CmaEs(const Eigen::VectorXd& mean0, const CmaEsOptions& options);

  /// Makes the first k columns of the next Ask() batch these candidates (projected onto the box),
  /// treated by the injection rule above. @param candidates [n x k], 1 <= k <= lambda, finite.
  /// Call before Ask(); replaces earlier injected candidates not yet asked.
  void Inject(const Eigen::MatrixXd& candidates);

  /// The batch to evaluate, [n x lambda], one candidate per column, inside the box. Calling Ask()
  /// again before Tell() returns the same batch. Throws once the run has stopped.
  const Eigen::MatrixXd& Ask();

  /// Reports the costs of the last Ask() batch and updates the distribution.
  /// @param costs [lambda] cost of column k (lower is better); NaN/inf allowed (ranked last).
  /// @return status() after the update.
  CmaEsStatus Tell(const Eigen::VectorXd& costs);

  CmaEsStatus status() const { return status_; }
  int dimension() const { return params_.n; }
  int population() const { return params_.lambda; }
  const CmaEsParameters& parameters() const { return params_; }
  const CmaEsOptions& options() const { return options_; }
  /// Distribution mean m [n] (may lie slightly outside the box, see above).
  const Eigen::VectorXd& mean() const { return mean_; }
  double sigma() const { return sigma_; }
  /// Covariance matrix C [n x n] (the distribution is N(m, sigma^2 C)).
  const Eigen::MatrixXd& covariance() const { return C_; }
  /// Condition number of C at the last eigendecomposition.
  double condition() const;
  /// Best evaluated candidate [n] (inside the box) and its cost; +inf before any finite cost.
  const Eigen::VectorXd& best_x() const { return best_x_; }
  double best_cost() const { return best_cost_; }
  std::int64_t evaluations() const { return evaluations_; }
  int generation() const { return generation_; }
  /// Number of NaN/inf costs received so far.
  std::int64_t non_finite_costs() const { return non_finite_costs_; }
  /// Generations in which the flat-fitness escape of tutorial B.4 increased sigma.
  int flat_generations() const { return flat_generations_; }

 private:
  void Decompose(bool* ok);
  Eigen::VectorXd Repair(const Eigen::VectorXd& x) const;
  void UpdateBoundWeights(const Eigen::VectorXd& costs);
  CmaEsStatus CheckStop();

  CmaEsOptions options_;
  CmaEsParameters params_;
  bool bounded_ = false;
  std::int64_t max_evaluations_ = 0;

  // Distribution state (tutorial Fig. 6).
  Eigen::VectorXd mean_, p_sigma_, p_c_;
  double sigma_ = 0;
  Eigen::MatrixXd C_, B_, inv_sqrt_C_;
  Eigen::VectorXd D_;  // sqrt of the eigenvalues of C
  std::int64_t eigen_evaluations_ = 0;

  // Current batch.
  bool asked_ = false;
  Eigen::MatrixXd X_;      // [n x lambda] returned by Ask (in the box)
  Eigen::MatrixXd X_raw_;  // unrepaired m + sigma y
  Eigen::MatrixXd Y_;      // steps y_k used by the update
  Eigen::MatrixXd injected_;
  std::vector<int> order_;
  Eigen::VectorXd ranked_costs_;

  // Bound penalty (Hansen et al. 2009).
  Eigen::VectorXd gamma_;
  bool gamma_adapting_ = false;
  std::vector<double> iqr_history_;

  // Termination bookkeeping.
  std::vector<double> best_history_;  // best ranked cost of recent generations

  Eigen::VectorXd best_x_;
  double best_cost_ = std::numeric_limits<double>::infinity();
  std::int64_t evaluations_ = 0;
  int generation_ = 0;
  std::int64_t non_finite_costs_ = 0;
  int flat_generations_ = 0;
  CmaEsStatus status_ = CmaEsStatus::kRunning;

  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_;
};

/// Outcome of Minimize.
struct CmaEsSummary {
  CmaEsStatus status = CmaEsStatus::kRunning;
  Eigen::VectorXd best_x;  ///< [n], inside the box
  double best_cost = std::numeric_limits<double>::infinity();
  std::int64_t evaluations = 0;
  int generations = 0;
  std::int64_t non_finite_costs = 0;
  double final_sigma = 0;
  /// One line: status, best cost, evaluations, generations, non-finite costs, final sigma.
  std::string BriefReport() const;
};

/// Runs CMA-ES on `f` from x0 until a stopping criterion holds, evaluating the batch sequentially.
/// @param f cost of a candidate [n] (inside the box); may return NaN/inf.
CmaEsSummary Minimize(const std::function<double(const Eigen::VectorXd&)>& f,
                      const Eigen::VectorXd& x0, const CmaEsOptions& options);

}  // namespace foresight::optim
