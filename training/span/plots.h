#pragma once
/// PNG figures of evaluations (OpenCV).

#include <string>

#include "datasets/windows.h"
#include "training/span/config.h"

namespace foresight::span {

/// A grid of panels: observed past (blue), ground-truth future (green), sampled futures (red),
/// predicted mean (dark red), for `eval.plot_tracks` windows spread over `test`.
void PlotSamples(const std::string& artifact, const WindowSet& test, const EvalConfig& eval,
                 const std::string& png_path);

}  // namespace foresight::span
