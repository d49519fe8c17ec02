#pragma once
/// Geometric Fabric Command Sequences (thesis ch 9, "Geometric Fabrics Command Optimisation"):
/// the GFCOP cost of a command sequence and SolveGFCOP (thesis Algorithm "SolveGFCOP with
/// warm-started CMA-ES"), with candidates rolled out in parallel.
///
/// A candidate y = [q_g^1; ...; q_g^n] (7n) holds the intermediate commands; the (n+1)-th command
/// is the global goal (errata: the final command is the goal). Rollouts run in sequence, each
/// starting from the terminal state of the previous one (thesis "intermediate continuity"):
///   cost(y) = sum_{i=1}^{n+1} t*_i + M [t*_{n+1} >= t_max]      (thesis eq. "Cost").
/// A rollout that collides, leaves the joint limits or becomes non-finite makes the candidate
/// infeasible: its cost is (n+1) t_max + M, above every collision-free candidate (the thesis's
/// cost has no collision term because its fabric never collides; ours reports when it does).
/// Pruning (GfcsParams::prune, not in the thesis): since a cost is never below its summed rollout
/// time, a last-batch candidate whose time passes the top_m-th best cost finished so far cannot be
/// in the top m; it is stopped there. The returned top m are exactly those of a full evaluation.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "inference/manipulation/fabric.h"
#include "inference/manipulation/joint_types.h"

namespace foresight::manipulation {

/// What SolveGfcop does after a batch in which no candidate reached the goal (not in the thesis).
/// Such a batch's costs rank failures only, by the time their rollouts took before the last one
/// timed out, which says nothing about where the goal is reachable from: CMA-ES told those costs
/// moves towards candidates that fail quickly. A restart instead draws the next batch uniformly in
/// the joint limits and starts a new CMA-ES run at it (also after a batch of a run that had reached
/// the goal earlier: the decision is per batch).
enum class GfcsRestart {
  kNone,     ///< tell CMA-ES every batch (the thesis's Algorithm "SolveGFCOP")
  kUniform,  ///< the next batch uniform in the joint limits, a new CMA-ES run
};
const config::EnumNames<GfcsRestart>& GfcsRestartNames();

struct GfcsParams {
  int commands = 2;       ///< n + 1 (thesis: two commands per problem)
  int batch_size = 20;    ///< candidates per batch (thesis at test time: 20)
  int batches = 1;        ///< batches evaluated (thesis reports 1 and 5)
  int top_m = 4;          ///< candidates returned (thesis: top-4 into the training buffer)
  double penalty = 100;   ///< M, added when the last command times out (s)
  double sigma0 = 0.5;    ///< CMA-ES initial step size after the first batch (rad)
  int threads = 0;        ///< rollout threads; 0: the hardware's
  std::int64_t seed = 0;  ///< sampler and CMA-ES seed
  /// Stop a candidate of the last batch once its rollout time exceeds the m-th best cost the
  /// batch has finished (its cost can only be higher). The top m are the same as without it.
  bool prune = true;
  GfcsRestart restart = GfcsRestart::kNone;  ///< after a batch that reached nothing

  template <class A>
  void Serialize(A* a) {
    a->Visit("commands", &commands, config::Range::Closed(1, 10),
             "commands in the sequence, the last being the goal (n + 1)");
    a->Visit("batch_size", &batch_size, config::Range::Closed(2, 10000), "candidates per batch");
    a->Visit("batches", &batches, config::Range::Closed(1, 1000), "batches evaluated");
    a->Visit("top_m", &top_m, config::Range::Closed(1, 10000), "best candidates returned");
    a->Visit("penalty", &penalty, config::Range::NonNegative(),
             "M: cost added when the last command times out (s)");
    a->Visit("sigma0", &sigma0, config::Range::Positive(), "CMA-ES initial step size (rad)");
    a->Visit("threads", &threads, config::Range::Closed(0, 256), "rollout threads (0: all cores)");
    a->Visit("seed", &seed, config::Range::Any(), "seed of the sampler and CMA-ES");
    a->Visit("prune", &prune, config::Range::Any(),
             "stop last-batch candidates whose time already exceeds the top_m-th best cost "
             "(same top_m, less time)");
    a->VisitEnum("restart", &restart, GfcsRestartNames(),
                 "after a batch in which no candidate reached the goal: none (tell CMA-ES, the "
                 "thesis) or uniform (draw the next batch uniformly, new CMA-ES run)");
  }
};

/// Start state and goal of one motion problem.
struct GfcsQuery {
  JointVector start = JointVector::Zero();
  JointVector start_velocity = JointVector::Zero();
  JointVector goal = JointVector::Zero();
};

/// Draws the first batch of candidates (thesis f_sampler). Uniform within the joint limits now;
/// the learned energy-model sampler plugs in here.
class CommandSampler {
 public:
  virtual ~CommandSampler() = default;
  virtual std::string name() const = 0;
  /// Fills `out` [7 (commands - 1) x count] with candidates for `query`.
  virtual void Sample(const GfcsQuery& query, int intermediate_commands, int count,
                      std::mt19937_64* rng, Eigen::MatrixXd* out) = 0;
};

/// Columns first .. cols-1 of `out` [7n x cols] drawn uniformly in the joint limits, column by
/// column, row by row (row i is joint i mod 7): the draws every sampler's uniform part makes.
void FillUniform(const JointVector& lower, const JointVector& upper, Eigen::Index first,
                 std::mt19937_64* rng, Eigen::MatrixXd* out);

class UniformSampler : public CommandSampler {
 public:
  UniformSampler(const JointVector& lower, const JointVector& upper);
  std::string name() const override { return "uniform"; }
  void Sample(const GfcsQuery& query, int intermediate_commands, int count, std::mt19937_64* rng,
              Eigen::MatrixXd* out) override;

 private:
  JointVector lower_, upper_;
};

/// A batch split between two samplers: the first round(share * count) candidates from `first`,
/// the rest from `rest` (both draw from the caller's generator, in that order). Neither is owned;
/// both must outlive the split.
class SplitSampler : public CommandSampler {
 public:
  /// share in [0, 1] (else Error).
  SplitSampler(CommandSampler* first, double share, CommandSampler* rest);
  std::string name() const override { return first_->name() + "+" + rest_->name(); }
  void Sample(const GfcsQuery& query, int intermediate_commands, int count, std::mt19937_64* rng,
              Eigen::MatrixXd* out) override;

 private:
  CommandSampler* first_;
  double share_;
  CommandSampler* rest_;
  Eigen::MatrixXd part_;
};

/// One evaluated command sequence.
struct GfcsCandidate {
  Eigen::VectorXd commands;  ///< y [7n]
  double cost = 0;           ///< GFCOP cost (s)
  double time = 0;           ///< sum of rollout times (s)
  bool reached = false;      ///< the goal was reached (within t_max) without collision
  bool feasible = true;      ///< no rollout collided, left the limits or became non-finite
  RolloutStatus last_status = RolloutStatus::kTimeout;  ///< status of the last rollout run
  /// Stopped once `time` exceeded the caller's bound: `cost` (= time) is a lower bound, and
  /// reached/feasible are unknown (false/true).
  bool pruned = false;
  int steps = 0;    ///< integration steps of its rollouts (the work it cost)
  int stalled = 0;  ///< of its rollouts, ended by the fabric's stall test (FabricParams)
};

/// Rolls out `commands` [7n] (then the goal) from the query's start state and prices the sequence
/// (`penalty` = M). When `path` is given every integration state is appended, the start included.
/// Once the summed rollout time exceeds `prune_above` the evaluation stops (`pruned`): a cost is
/// never below the summed time, so the candidate costs more than `prune_above`.
GfcsCandidate EvaluateCommandSequence(const Fabric& fabric, const GfcsQuery& query,
                                      const Eigen::VectorXd& commands, double penalty,
                                      FabricWorkspace* ws, std::vector<JointVector>* path = nullptr,
                                      double prune_above = std::numeric_limits<double>::infinity());

enum class GfcsStatus {
  kSolved,     ///< the best candidate reaches the goal
  kNotSolved,  ///< no candidate reached the goal
  kError,      ///< bad input (see message); nothing was evaluated
};
const char* ToString(GfcsStatus status);

/// How the evaluated candidates of a solve ended, by the status of their last rollout (a pruned
/// candidate counts as kStopped): where a solve's budget went.
using RolloutStatusCounts = std::array<int, kRolloutStatusCount>;

struct GfcsSolution {
  GfcsStatus status = GfcsStatus::kNotSolved;
  std::string message;
  std::vector<GfcsCandidate> top;  ///< best first, at most top_m
  /// The sampler's batch (the first) as evaluated, in draw order: which of the sampler's own
  /// proposals reached the goal and which failed (the self-supervised loop's labelled failures).
  std::vector<GfcsCandidate> first_batch;
  int evaluations = 0;
  int pruned = 0;  ///< of the evaluations, stopped early (GfcsParams::prune)
  /// Every evaluated candidate's last status (a candidate reached the goal iff it is counted in
  /// kReached; intermediate timeouts are allowed). With penalty >= commands t_max, the solve is
  /// solved iff the kReached count is positive.
  RolloutStatusCounts candidate_statuses{};
  long long integration_steps = 0;  ///< fabric steps over every evaluated candidate
  int stalled_rollouts = 0;         ///< rollouts ended by the fabric's stall test
  double solve_time_s = 0;          ///< wall time of SolveGfcop
  /// Of solve_time_s, the sampler's first batch (SGLD for the learned sampler; 0 without one).
  double sample_time_s = 0;
  int restarts = 0;  ///< batches drawn afresh after a batch that reached nothing (restart)
  bool solved() const { return status == GfcsStatus::kSolved; }
};

/// SolveGFCOP: the first batch from `sampler`, later batches from CMA-ES (which is told the first
/// batch's costs; with params.restart uniform, a batch that reached nothing is followed by a
/// uniform batch and a new CMA-ES run instead), candidates of a batch rolled out on
/// `params.threads` threads.
GfcsSolution SolveGfcop(const Fabric& fabric, const GfcsQuery& query, CommandSampler* sampler,
                        const GfcsParams& params);

}  // namespace foresight::manipulation
