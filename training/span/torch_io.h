#pragma once
/// Rebuilds the LibTorch SpanNet from an exported artifact (parity tests, benchmarks).

#include <string>

#include "models/span/span_net.h"
#include "training/span/config.h"

namespace foresight::span {

struct LoadedNet {
  ExperimentConfig config;
  HeadLayout layout;
  Net net{nullptr};
};

/// Reads the config and the weights of `artifact` into a new SpanNet (eval mode).
LoadedNet LoadNetFromArtifact(const std::string& artifact);

}  // namespace foresight::span
