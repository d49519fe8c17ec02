#pragma once
/// Trainer settings shared by every neural model (torch-free header).

#include <cstdint>

#include "core/config.h"

namespace foresight {

enum class LrSchedule { kConstant, kStep, kCosine };
enum class ProgressStyle { kAuto, kBar, kLines, kNone };

struct TrainConfig {
  int epochs = 150;
  int batch_size = 256;
  double learning_rate = 1e-3;
  double weight_decay = 0.0;
  LrSchedule schedule = LrSchedule::kCosine;
  int step_every = 50;           ///< epochs between step decays (schedule: step)
  double step_factor = 0.5;      ///< lr multiplier per step (schedule: step)
  double min_lr_ratio = 0.02;    ///< final lr / initial lr (schedule: cosine)
  double grad_clip_norm = 10.0;  ///< 0 disables clipping
  int patience = 25;             ///< epochs without validation improvement before stopping; 0 never
  double min_delta = 1e-4;       ///< improvement smaller than this does not count
  int threads = 1;  ///< intra-op threads of LibTorch (results are bit-identical per count)
  ProgressStyle progress = ProgressStyle::kAuto;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("epochs", &epochs, Range::AtLeast(1), "maximum number of epochs");
    a->Visit("batch_size", &batch_size, Range::AtLeast(1), "minibatch size");
    a->Visit("learning_rate", &learning_rate, Range::Positive(), "Adam learning rate");
    a->Visit("weight_decay", &weight_decay, Range::NonNegative(), "Adam L2 weight decay");
    a->VisitEnum("schedule", &schedule,
                 config::EnumNames<LrSchedule>{{LrSchedule::kConstant, "constant"},
                                               {LrSchedule::kStep, "step"},
                                               {LrSchedule::kCosine, "cosine"}},
                 "learning-rate schedule over epochs");
    a->Visit("step_every", &step_every, Range::AtLeast(1), "epochs per decay (schedule: step)");
    a->Visit("step_factor", &step_factor, Range::OpenClosed(0, 1), "decay factor (schedule: step)");
    a->Visit("min_lr_ratio", &min_lr_ratio, Range::Closed(0, 1),
             "final / initial learning rate (schedule: cosine)");
    a->Visit("grad_clip_norm", &grad_clip_norm, Range::NonNegative(),
             "clip the global gradient norm to this value (0: off)");
    a->Visit("patience", &patience, Range::AtLeast(0),
             "early stopping: epochs without validation improvement (0: off)");
    a->Visit("min_delta", &min_delta, Range::NonNegative(), "smallest validation improvement");
    a->Visit("threads", &threads, Range::Closed(1, 256), "LibTorch intra-op threads");
    a->VisitEnum("progress", &progress,
                 config::EnumNames<ProgressStyle>{{ProgressStyle::kAuto, "auto"},
                                                  {ProgressStyle::kBar, "bar"},
                                                  {ProgressStyle::kLines, "lines"},
                                                  {ProgressStyle::kNone, "none"}},
                 "progress display (auto: a bar on a terminal, plain lines otherwise)");
  }
};

/// Learning rate at `epoch` (0-based) of `config.epochs`.
double LearningRateAt(const TrainConfig& config, int epoch);

}  // namespace foresight
