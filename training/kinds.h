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

// One function per method, each in its training/<method>/kind.cc (in the method's namespace where
// it has one).
namespace occupancy {
ExperimentKind Kind();
void SetBenchStep(ExperimentKind* kind);  // in training/occupancy/bench.cc
}  // namespace occupancy
namespace directional {
ExperimentKind Kind();
void SetBenchStep(ExperimentKind* kind);
}  // namespace directional
namespace span {
/// `embedded_default`: the config `train default` runs (configs/quickstart.yaml).
ExperimentKind Kind(const std::string& embedded_default);
void SetBenchStep(ExperimentKind* kind);
}  // namespace span
namespace nav {  // closed-loop navigation episodes
ExperimentKind Kind();
}  // namespace nav
namespace manipulation {  // the manipulation planning harness
ExperimentKind Kind();
void SetBenchStep(ExperimentKind* kind);
}  // namespace manipulation
namespace gfcs {
ExperimentKind Kind();
}  // namespace gfcs
namespace imitation {  // diffeomorphic templates
ExperimentKind Kind();
void SetBenchStep(ExperimentKind* kind);
}  // namespace imitation
namespace otnet {
ExperimentKind Kind();
void SetBenchStep(ExperimentKind* kind);
}  // namespace otnet
namespace constrained {
ExperimentKind Kind();
}  // namespace constrained

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

/// A kind's bench options: `bench.key=value` arguments (request.options, prefix stripped) read
/// strictly into Options (an unknown key or a value out of range is an Error naming it).
template <typename Options>
Options LoadBenchOptions(const BenchRequest& req) {
  return config::FromYaml<Options>(YAML::Node(YAML::NodeType::Map), "bench options", req.options);
}

/// Gives a kind its bench step: `run` with the request and its options (LoadBenchOptions), and
/// the options' reference table.
template <typename Options>
void SetBench(ExperimentKind* kind, void (*run)(const BenchRequest&, const Options&)) {
  kind->bench_reference = [] { return config::ReferenceTable<Options>(); };
  kind->bench = [run](const BenchRequest& req) { run(req, LoadBenchOptions<Options>(req)); };
}

/// The config a bench builds from: the config target, or the run directory's config.yaml (plus
/// overrides). An artifact target is an Error: this kind's bench times what a config builds.
template <typename Config>
Config LoadBenchConfig(const BenchRequest& req) {
  FS_THROW_UNLESS(req.what != BenchRequest::Target::kArtifact, req.target,
                  ": this bench builds what it times from a config; name the config or a run "
                  "directory, not an artifact");
  if (req.what == BenchRequest::Target::kRunDir)
    return LoadRunConfig<Config>(req.target, req.overrides);
  return config::LoadExperimentConfig<Config>(req.target, req.overrides);
}

}  // namespace foresight
