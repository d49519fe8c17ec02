#pragma once
/// Progress of long work: a bar with rate, ETA and loss on a terminal, plain lines otherwise.

#include <chrono>
#include <string>

#include "training/train_config.h"

namespace foresight {

class Progress {
 public:
  /// @param total number of steps (epochs); @param unit name of the work items counted by rate.
  Progress(ProgressStyle style, int total, std::string unit);
  /// Within an epoch: fraction done in [0, 1], items processed since start, running loss.
  void Update(int step, double fraction, double items, double loss);
  /// End of a step (epoch) with its summary text.
  void EndStep(int step, const std::string& summary);
  void Finish();

 private:
  bool bar_ = false, lines_ = false;
  int total_;
  std::string unit_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  int first_step_ = -1;
};

}  // namespace foresight
