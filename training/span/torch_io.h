#pragma once
/// Rebuilds the LibTorch SpanNet from an exported artifact (parity tests, benchmarks).

#include <string>

#include "models/span/span_net.h"
#include "training/span/config.h"

namespace foresight {

struct LoadedSpanNet {
  SpanExperimentConfig config;
  HeadLayout layout;
  SpanNet net{nullptr};
};

/// Reads the config and the weights of `artifact` into a new SpanNet (eval mode).
LoadedSpanNet LoadSpanNetFromArtifact(const std::string& artifact);

}  // namespace foresight
