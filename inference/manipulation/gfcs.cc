#include "inference/manipulation/gfcs.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <thread>

#include "core/bench.h"
#include "core/error.h"
#include "inference/optim/cmaes.h"

namespace foresight::manipulation {
namespace {

/// The m-th lowest cost among the candidates finished so far (+inf before m have finished),
/// shared by the rollout threads of a batch.
class TopCostBound {
 public:
  explicit TopCostBound(int m) : m_(m) { best_.reserve(static_cast<std::size_t>(m) + 1); }
  double Get() const { return bound_.load(std::memory_order_relaxed); }
  void Offer(double cost) {
    const std::lock_guard<std::mutex> lock(mutex_);
    best_.insert(std::upper_bound(best_.begin(), best_.end(), cost), cost);
    if (static_cast<int>(best_.size()) > m_) best_.pop_back();
    if (static_cast<int>(best_.size()) == m_) bound_.store(best_.back(), std::memory_order_relaxed);
  }

 private:
  const int m_;
  std::mutex mutex_;
  std::vector<double> best_;  ///< ascending, at most m
  std::atomic<double> bound_{std::numeric_limits<double>::infinity()};
};

/// Evaluates the columns of `candidates` on `workspaces.size()` threads into `out`. With `prune_m`
/// > 0 a candidate stops once its time exceeds the prune_m-th best finished cost: which ones stop
/// depends on the threads' timing, the prune_m best (exact) candidates do not.
void EvaluateBatch(const Fabric& fabric, const GfcsQuery& query, const Eigen::MatrixXd& candidates,
                   double penalty, int prune_m, std::vector<FabricWorkspace>* workspaces,
                   std::vector<GfcsCandidate>* out) {
  const int count = static_cast<int>(candidates.cols());
  out->resize(count);
  std::atomic<int> next{0};
  TopCostBound bound(std::max(prune_m, 1));
  auto work = [&](FabricWorkspace* ws) {
    for (int i = next++; i < count; i = next++) {
      const double prune_above =
          prune_m > 0 ? bound.Get() : std::numeric_limits<double>::infinity();
      GfcsCandidate& c = (*out)[i];
      c = EvaluateCommandSequence(fabric, query, candidates.col(i), penalty, ws, nullptr,
                                  prune_above);
      if (prune_m > 0 && !c.pruned) bound.Offer(c.cost);
    }
  };
  const int threads = std::min<int>(static_cast<int>(workspaces->size()), count);
  std::vector<std::thread> pool;
  pool.reserve(std::max(0, threads - 1));
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, &(*workspaces)[t]);
  work(&(*workspaces)[0]);
  for (std::thread& th : pool) th.join();
}

}  // namespace

const char* ToString(GfcsStatus status) {
  switch (status) {
    case GfcsStatus::kSolved:
      return "solved";
    case GfcsStatus::kNotSolved:
      return "not_solved";
    case GfcsStatus::kError:
      return "error";
  }
  return "unknown";
}

UniformSampler::UniformSampler(const JointVector& lower, const JointVector& upper)
    : lower_(lower), upper_(upper) {
  FS_THROW_UNLESS((lower.array() < upper.array()).all(),
                  "uniform sampler: every lower joint limit must be below the upper one");
}

void FillUniform(const JointVector& lower, const JointVector& upper, Eigen::Index first,
                 std::mt19937_64* rng, Eigen::MatrixXd* out) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (Eigen::Index c = first; c < out->cols(); ++c)
    for (Eigen::Index i = 0; i < out->rows(); ++i)
      (*out)(i, c) = lower[i % kDof] + unit(*rng) * (upper[i % kDof] - lower[i % kDof]);
}

void UniformSampler::Sample(const GfcsQuery& /*query*/, int intermediate_commands, int count,
                            std::mt19937_64* rng, Eigen::MatrixXd* out) {
  out->resize(kDof * intermediate_commands, count);
  FillUniform(lower_, upper_, 0, rng, out);
}

SplitSampler::SplitSampler(CommandSampler* first, double share, CommandSampler* rest)
    : first_(first), share_(share), rest_(rest) {
  FS_THROW_UNLESS(first && rest, "split sampler: both samplers must be given");
  FS_THROW_UNLESS(share >= 0 && share <= 1, "split sampler: share ", share, " is outside [0, 1]");
}

void SplitSampler::Sample(const GfcsQuery& query, int intermediate_commands, int count,
                          std::mt19937_64* rng, Eigen::MatrixXd* out) {
  FS_THROW_UNLESS(count >= 0, "split sampler: count ", count, " is negative");
  const int n_first = static_cast<int>(std::lround(share_ * static_cast<double>(count)));
  out->resize(kDof * intermediate_commands, count);
  if (n_first > 0) {
    first_->Sample(query, intermediate_commands, n_first, rng, &part_);
    out->leftCols(n_first) = part_;
  }
  if (count - n_first > 0) {
    rest_->Sample(query, intermediate_commands, count - n_first, rng, &part_);
    out->rightCols(count - n_first) = part_;
  }
}

const config::EnumNames<GfcsRestart>& GfcsRestartNames() {
  static const config::EnumNames<GfcsRestart> names = {{GfcsRestart::kNone, "none"},
                                                       {GfcsRestart::kUniform, "uniform"}};
  return names;
}

GfcsCandidate EvaluateCommandSequence(const Fabric& fabric, const GfcsQuery& query,
                                      const Eigen::VectorXd& commands, double penalty,
                                      FabricWorkspace* ws, std::vector<JointVector>* path,
                                      double prune_above) {
  const int intermediate = static_cast<int>(commands.size() / kDof);
  GfcsCandidate c;
  c.commands = commands;
  JointVector q = query.start, qd = query.start_velocity;
  if (path) path->push_back(q);
  for (int i = 0; i <= intermediate; ++i) {
    const JointVector command =
        i < intermediate ? JointVector(commands.segment<kDof>(i * kDof)) : query.goal;
    const RolloutResult r =
        fabric.Rollout(q, qd, command, ws, path, prune_above - c.time,
                       i < intermediate ? CommandRole::kVia : CommandRole::kGoal);
    c.time += r.t;
    c.steps += r.steps;
    c.stalled += r.stalled;
    c.last_status = r.status;
    if (r.status == RolloutStatus::kStopped) {
      c.pruned = true;
      c.cost = c.time;
      return c;
    }
    if (!r.ok()) {  // collision, joint limit or non-finite: infeasible, worse than any timeout
      c.feasible = false;
      c.cost = (intermediate + 1) * fabric.params().t_max + penalty;
      return c;
    }
    q = r.q;
    qd = r.qd;
    if (i == intermediate) c.reached = r.status == RolloutStatus::kReached;
  }
  c.cost = c.time + (c.reached ? 0.0 : penalty);
  return c;
}

GfcsSolution SolveGfcop(const Fabric& fabric, const GfcsQuery& query, CommandSampler* sampler,
                        const GfcsParams& params) {
  const auto started = bench::Clock::now();
  GfcsSolution solution;
  const JointLimits& limits = fabric.robot().limits();
  const int intermediate = params.commands - 1;
  auto fail = [&](const std::string& message) {
    solution.status = GfcsStatus::kError;
    solution.message = message;
    return solution;
  };
  if (!query.start.allFinite() || !query.start_velocity.allFinite() || !query.goal.allFinite())
    return fail("non-finite start, start velocity or goal");
  if (params.commands < 1 || params.batch_size < 2 || params.batches < 1 || params.top_m < 1)
    return fail("commands, batch_size, batches and top_m must be >= 1 (batch_size >= 2)");
  // Pruning relies on a cost never being below its summed rollout time.
  if (!(params.penalty >= 0)) return fail("penalty M must be >= 0");

  std::vector<FabricWorkspace> workspaces;
  const int threads = params.threads > 0
                          ? params.threads
                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  for (int t = 0; t < threads; ++t) workspaces.push_back(fabric.MakeWorkspace());

  std::vector<GfcsCandidate> all, batch;
  std::mt19937_64 rng(static_cast<std::uint64_t>(params.seed));
  Eigen::MatrixXd candidates;
  if (intermediate == 0) {  // a single command: the goal itself; nothing to optimise
    candidates.resize(0, 1);
    EvaluateBatch(fabric, query, candidates, params.penalty, /*prune_m=*/0, &workspaces, &batch);
    all = batch;
    solution.first_batch = batch;
  } else {
    const auto sample_started = bench::Clock::now();
    sampler->Sample(query, intermediate, params.batch_size, &rng, &candidates);
    solution.sample_time_s = bench::SecondsSince(sample_started);
    optim::CmaEsOptions options;
    options.population = params.batch_size;
    options.sigma0 = params.sigma0;
    options.seed = static_cast<std::uint64_t>(params.seed);
    options.lower = limits.lower.replicate(intermediate, 1);
    options.upper = limits.upper.replicate(intermediate, 1);
    const Eigen::VectorXd mean0 = 0.5 * (options.lower + options.upper);
    optim::CmaEs es(mean0, options);
    es.Inject(candidates);
    UniformSampler uniform(limits.lower, limits.upper);
    for (int b = 0; b < params.batches; ++b) {
      const Eigen::MatrixXd& asked = es.Ask();
      // CMA-ES ranks every cost it is told: only the last batch (told nothing) is pruned.
      const bool last = b + 1 == params.batches;
      EvaluateBatch(fabric, query, asked, params.penalty, last && params.prune ? params.top_m : 0,
                    &workspaces, &batch);
      Eigen::VectorXd costs(static_cast<Eigen::Index>(batch.size()));
      for (std::size_t i = 0; i < batch.size(); ++i)
        costs[static_cast<Eigen::Index>(i)] = batch[i].cost;
      all.insert(all.end(), batch.begin(), batch.end());
      if (b == 0) solution.first_batch = batch;
      if (last) break;
      const bool reached_nothing = std::none_of(batch.begin(), batch.end(),
                                                [](const GfcsCandidate& c) { return c.reached; });
      if (reached_nothing && params.restart == GfcsRestart::kUniform) {
        uniform.Sample(query, intermediate, params.batch_size, &rng, &candidates);
        ++solution.restarts;
        options.seed = static_cast<std::uint64_t>(params.seed) + 7919ULL * solution.restarts;
        es = optim::CmaEs(mean0, options);
        es.Inject(candidates);
      } else if (es.Tell(costs) != optim::CmaEsStatus::kRunning) {
        break;
      }
    }
  }
  solution.evaluations = static_cast<int>(all.size());
  solution.pruned = static_cast<int>(
      std::count_if(all.begin(), all.end(), [](const GfcsCandidate& c) { return c.pruned; }));
  for (const GfcsCandidate& c : all) {
    ++solution.candidate_statuses[static_cast<int>(c.last_status)];
    solution.integration_steps += c.steps;
    solution.stalled_rollouts += c.stalled;
  }
  // Pruned candidates cost more than the top_m-th exact cost of their batch: they sort last, so the
  // top m are those of an unpruned solve.
  std::stable_sort(all.begin(), all.end(), [](const GfcsCandidate& a, const GfcsCandidate& b) {
    if (a.pruned != b.pruned) return b.pruned;
    return a.cost < b.cost;
  });
  if (static_cast<int>(all.size()) > params.top_m)
    all.resize(static_cast<std::size_t>(params.top_m));
  solution.top = std::move(all);
  solution.status = !solution.top.empty() && solution.top.front().reached ? GfcsStatus::kSolved
                                                                          : GfcsStatus::kNotSolved;
  solution.solve_time_s = bench::SecondsSince(started);
  return solution;
}

}  // namespace foresight::manipulation
