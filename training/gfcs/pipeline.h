#pragma once
/// The gfcs kind's steps (thesis ch 9): encode the training problems (basis point set, then an
/// autoencoder trained by the trainer), run the self-supervised loop, export the energy model
/// with its encoder to one artifact, and evaluate the learned sampler against the uniform one
/// (and the baselines) on held-out problems through the plan harness.

#include <atomic>
#include <string>
#include <vector>

#include "training/gfcs/config.h"
#include "training/manipulation/plan.h"

namespace foresight::gfcs {

/// Files of a gfcs run directory (a resumable kind).
inline constexpr const char* kGfcsArtifact = "model.h5";

/// Trains into `run_dir` (resuming when `resume`) and exports run_dir/model.h5. @return false
/// when interrupted (the checkpoints stay valid).
/// With `check_eval_sets` the held-out sets are loaded first, so a missing file fails before the
/// loop rather than after it (off for runs that will not be evaluated).
bool TrainRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
              const std::atomic<bool>* interrupt, bool check_eval_sets = true);

/// Writes run_dir/model.h5 from the loop's last checkpoint. @return its path.
std::string ExportRun(const std::string& run_dir);

/// Paired learned-minus-uniform differences, one value per problem: the mean over the problem's
/// draws (PlanAttempt::repeat) that both methods ran. success over every pair; time_s where
/// neither errored (an error takes no time); cost where both have a GFCOP cost (the penalty of an
/// unsolved problem included), cost_solved where both also solved. The draws of a problem are not
/// independent samples of the problem set, so intervals resample these per-problem values.
struct PairedPerProblem {
  std::vector<double> success, time, cost, cost_solved;
  int only_learned = 0, only_uniform = 0;  ///< draws solved by one of the two only
};
PairedPerProblem PairPerProblem(const std::vector<manipulation::PlanAttempt>& attempts,
                                const std::string& uniform, const std::string& learned);

/// Held-out evaluation of run_dir/model.h5: run_dir/eval/<set>/ (the plan harness's files) and
/// run_dir/eval.json (per family and method: success, lengths, LDJ, times; the learned-minus-
/// uniform paired cost difference with its 95 % bootstrap interval). @return eval.json's text.
std::string EvaluateRun(const ExperimentConfig& c, const std::string& run_dir);

}  // namespace foresight::gfcs
