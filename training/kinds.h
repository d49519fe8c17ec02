#pragma once
/// The experiment kinds of this build (training/experiment.h) and the helpers every kind uses to
/// read its config. Torch-free header: the LibTorch kinds exist only in builds with LibTorch.

#include <string>
#include <vector>

#include "core/config.h"
#include "training/experiment.h"

namespace foresight {

/// Every kind this build has; `train default` runs the SPAN predictor quickstart (builds with
/// LibTorch; a build without it has no default).
ExperimentRegistry BuiltinKinds();

// One function per method, each in its <method>_kind.cc.
ExperimentKind OccupancyKind();
ExperimentKind NavigationKind();
ExperimentKind ManipulationKind();
#ifdef FORESIGHT_WITH_TORCH
ExperimentKind SpanKind(const std::string& embedded_default);
ExperimentKind DirectionalKind();
ExperimentKind GfcsKind();
ExperimentKind DiffeoKind();
ExperimentKind OtnetKind();
ExperimentKind ConstrainedKind();
#endif

/// The config of a train request: the file, or `embedded_default` (named `default_name` in
/// errors) when the request says "default".
template <typename Config>
Config LoadRequestConfig(const TrainRequest& req, const std::string& embedded_default,
                         const std::string& default_name) {
  if (req.config.empty() || req.config == "default")
    return config::ExperimentConfigFromYaml<Config>(
        embedded_default, "<embedded " + default_name + ">", req.overrides);
  return config::LoadExperimentConfig<Config>(req.config, req.overrides);
}

/// The config a run was started with (run_dir/config.yaml), plus overrides (e.g. data.root).
template <typename Config>
Config LoadRunConfig(const std::string& run_dir, const std::vector<std::string>& overrides) {
  return config::LoadExperimentConfig<Config>(run_dir + "/config.yaml", overrides);
}

}  // namespace foresight
