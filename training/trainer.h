#pragma once
/// A config-driven minibatch trainer for any LibTorch model: Adam, learning-rate schedule,
/// gradient clipping, early stopping on the validation loss, non-finite loss detection,
/// atomic per-epoch checkpoints, bit-identical --resume, progress display and metrics.csv.

#include <torch/torch.h>

#include <atomic>
#include <functional>
#include <string>

#include "training/train_config.h"

namespace foresight {

namespace dist {
class Group;  // training/distributed.h
}

/// What the trainer trains: a module, a batch loss and a validation loss.
class TrainingTask {
 public:
  virtual ~TrainingTask() = default;
  virtual torch::nn::Module& module() = 0;
  virtual std::int64_t num_train() const = 0;
  /// Mean loss over the training samples `indices` [B] (int64), with autograd.
  virtual torch::Tensor BatchLoss(const torch::Tensor& indices) = 0;
  /// Mean validation loss (evaluated without gradients).
  virtual double ValidationLoss() = 0;
};

enum class TerminationReason {
  kMaxEpochs,
  kEarlyStopped,
  kNonFiniteLoss,
  kInterrupted,
  kAlreadyComplete
};
const char* ToString(TerminationReason reason);

/// Outcome of a training run (expected outcomes are values, not exceptions).
struct TrainingSummary {
  TerminationReason reason = TerminationReason::kMaxEpochs;
  int epochs_completed = 0;  ///< including epochs of a resumed run
  int best_epoch = -1;       ///< 1-based epoch of the best validation loss
  double best_val_loss = 0;
  double last_train_loss = 0;
  double seconds = 0;  ///< wall time of this invocation
  double samples_per_second = 0;
  std::string BriefReport() const;
  /// One JSON object (training_summary.json); non-finite numbers (no epoch completed) are null.
  std::string ToJson() const;
};

/// Writes `s` to `path` (training_summary.json) atomically. A run resumed after it had finished
/// (reason kAlreadyComplete) keeps the summary its finishing invocation wrote, if there is one.
void WriteTrainingSummary(const std::string& path, const TrainingSummary& s);

/// Files of a run directory.
struct RunPaths {
  std::string dir;
  std::string Checkpoint() const { return dir + "/checkpoints/last.pt"; }
  std::string BestCheckpoint() const { return dir + "/checkpoints/best.pt"; }
  std::string Metrics() const { return dir + "/metrics.csv"; }
};

/// Ways to stop a run from outside; the last checkpoint stays valid (resume continues from it).
struct TrainHooks {
  /// Polled between batches (e.g. set by SIGINT); a partial epoch is discarded.
  const std::atomic<bool>* interrupt = nullptr;
  /// Called after each completed epoch with the number completed; false stops the run.
  std::function<bool(int)> continue_after_epoch;
};

/// While alive, SIGINT and SIGTERM set flag() (for TrainHooks::interrupt) instead of ending the
/// process; the handlers that were there before are restored on destruction. One at a time.
/// The flag is polled between batches, so a signal during loading or model building waits for
/// the first batch; a second signal ends the process at once (the default action: a run loses at
/// most its epoch in progress, as with kill -9).
class ScopedInterruptFlag {
 public:
  ScopedInterruptFlag();
  ~ScopedInterruptFlag();
  ScopedInterruptFlag(const ScopedInterruptFlag&) = delete;
  ScopedInterruptFlag& operator=(const ScopedInterruptFlag&) = delete;
  const std::atomic<bool>* flag() const;

 private:
  using Handler = void (*)(int);
  Handler previous_int_, previous_term_;
};

/// Trains `task` in `run`. With `resume`, continues from run.Checkpoint() (an Error if it is
/// missing or corrupt) and produces the same parameters as an uninterrupted run. Each epoch
/// appends its metrics.csv row, then replaces the checkpoints (fsynced, atomic rename); a resume
/// drops rows after the checkpoint's epoch.
///
/// Data parallel when `group` (default: dist::DefaultGroup(), i.e. the launch environment) has
/// more than one rank (docs/distributed.md): every rank must call Train with the same task data,
/// config and seed. Each global batch is split into contiguous slices, one per rank, and the
/// gradients are all-reduced so that every step equals the single-process step on the global
/// batch (to float rounding). Rank 0's parameters are broadcast at the start (and after a resume,
/// whose checkpoint only rank 0 reads); rank 0 alone computes the validation loss, writes metrics
/// and checkpoints, and decides every stop. A failed peer is an Error on the other ranks.
TrainingSummary Train(TrainingTask* task, const TrainConfig& config, const RunPaths& run,
                      std::uint64_t seed, bool resume, const TrainHooks& hooks = {},
                      dist::Group* group = nullptr);

/// Loads the model parameters of a checkpoint into `module`; corrupt files are an Error.
void LoadCheckpointModel(const std::string& path, torch::nn::Module* module);

}  // namespace foresight
