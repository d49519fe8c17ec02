#pragma once
/// The self-supervised GFCS loop (thesis Algorithm "Self-supervised GFCS"): solve each training
/// problem with the current sampler, keep the top solutions in a buffer, every `train_every`
/// solves draw SGLD negatives and train the energy model with InfoNCE, then sample by SGLD on it.
///
/// Resumable: after every `checkpoint_every` solves the whole state (buffer, kept failures, model,
/// optimiser, counters, encoder) is written atomically to checkpoints/loop[.rank<r>].pt. Every
/// random stream is derived from (seed, counter) - solve s uses seed + s, training round k and its
/// negatives use (seed, k) - so a resumed run draws exactly what an uninterrupted one would.
///
/// Ranks (training/distributed.h): the solves of a block of `train_every` are dealt round-robin
/// over the ranks and the new positives gathered in solve order; the negatives are dealt over the
/// ranks and gathered; the training round itself runs on every rank alike (not split: a split
/// batch sums in another order, and the float-level difference grows through the learned
/// sampler's solves). With the same thread counts any number of ranks ends with exactly the
/// model of one.

#include <torch/torch.h>

#include <Eigen/Core>
#include <atomic>
#include <string>
#include <vector>

#include "inference/engine/dense.h"
#include "inference/manipulation/energy_model.h"
#include "inference/manipulation/mbm_problem.h"
#include "inference/manipulation/robot_model.h"
#include "models/gfcs/gfcs_nets.h"
#include "training/gfcs/config.h"

namespace foresight::gfcs {

/// A training problem with its context (encoded once, after the autoencoder).
struct TrainingProblem {
  std::string family;
  manipulation::ManipulationProblem problem;
  Eigen::VectorXf context;
};

/// The problem encoding fixed before the loop: BPS normalisation and the trained encoder.
struct Encoding {
  Eigen::VectorXf bps_mean, bps_std;
  Mlp encoder;
};

/// One positive: a command sequence (normalised to [-1, 1]) that solved `problem` (the same
/// record holds a kept failure, loop.failure_negatives: a first-batch candidate that did not).
struct Positive {
  int problem = 0;  ///< index into the training problems
  int solve = 0;    ///< the solve that produced it
  float cost = 0;   ///< GFCOP cost (s)
  Eigen::VectorXf u;
};

struct LoopStats {
  int solves = 0, solved = 0, rounds = 0;
  double last_loss = 0;
  double solve_seconds = 0, negative_seconds = 0, train_seconds = 0;  ///< this invocation
  /// wall time of this invocation's loop (solves, waits for other ranks, training rounds,
  /// checkpoints), without the set-up before it (problems, encoding, autoencoder)
  double loop_seconds = 0;
  int dropped_particles = 0;  ///< non-finite SGLD particles (sampler and negatives)
  int sampler_failures = 0;   ///< solves where the learned sampler failed (uniform instead)
  /// first-batch failures kept as negatives (loop.failure_negatives), over the whole loop
  int failures_kept = 0;
  bool interrupted = false;
  std::string ToJson() const;
};

/// Energy model parts of a network state (for the engine: sampler, negatives, export).
manipulation::EnergyModelParts MakeEnergyParts(const ExperimentConfig& c,
                                               const manipulation::RobotModel& robot,
                                               const Encoding& encoding, const Mlp& energy);

/// Runs (or resumes: `resume` and a checkpoint exist) the loop in `run_dir` over `problems`
/// (contexts filled). @return the final network as engine weights in `*energy`, and every
/// solution the loop found with its problem's context in `*memory` (the nearest-neighbour
/// sampler's).
LoopStats RunSelfSupervisedLoop(const ExperimentConfig& c, const std::string& config_yaml,
                                const manipulation::RobotModel& robot, const Encoding& encoding,
                                const std::vector<TrainingProblem>& problems,
                                const std::string& run_dir, bool resume,
                                const std::atomic<bool>* interrupt, Mlp* energy,
                                manipulation::SolutionMemory* memory);

/// The final energy network, the encoding and the solution memory of a loop checkpoint (for
/// export).
void LoadLoopResult(const ExperimentConfig& c, const std::string& config_yaml,
                    const std::string& run_dir, Encoding* encoding, Mlp* energy,
                    manipulation::SolutionMemory* memory);

/// The loop checkpoint of `rank` in `run_dir`.
std::string LoopCheckpointPath(const std::string& run_dir, int rank);

}  // namespace foresight::gfcs
