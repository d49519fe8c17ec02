#pragma once
/// The one contract every method plugs into (docs/architecture.md): an experiment kind, registered
/// under the `model:` tag of its YAML configs, with its steps. The command line looks the kind up
/// from the config (train) or from the run directory's config.yaml (export, eval) and dispatches;
/// no command names a method. Torch-free.

#include <functional>
#include <string>
#include <vector>

namespace foresight {

/// What `foresight train` asks of a kind.
struct TrainRequest {
  std::string config;                  ///< config file, or "default" for the kind's embedded config
  std::vector<std::string> overrides;  ///< `key.path=value`
  std::string run_dir;                 ///< the run directory (created; see StartRunDirectory)
  bool resume = false;                 ///< continue the run in run_dir (kinds with `resumable`)
  bool evaluate = true;                ///< evaluate after export
};

/// What `foresight bench` asks of a kind. The target is a config file (benches that build what they
/// time: occupancy maps, the manipulation runtime), a run directory (its config.yaml or its
/// artifact) or an exported artifact (.h5; its kind is the `model:` of the config stored in it).
struct BenchRequest {
  enum class Target { kConfig, kRunDir, kArtifact };
  std::string target;
  Target what = Target::kConfig;
  std::vector<std::string> overrides;  ///< `key.path=value` of the config
  std::vector<std::string> options;  ///< the kind's bench options (`bench.` stripped): `repeats=5`
  bool json = false;                 ///< print one JSON object instead of a table
};

/// One method's steps. An empty step is one the kind does not have: the command says so in one
/// line. Steps report expected failures as foresight::Error with what and where.
struct ExperimentKind {
  std::string tag;             ///< the `model:` value of its configs (a family: `occupancy.`)
  bool tag_is_prefix = false;  ///< `tag` is a prefix (`occupancy.` matches occupancy.fast_bhm)
  std::string summary;         ///< one line: the method and its thesis chapter
  std::string configs;     ///< where its configs live (for the reference), e.g. configs/span/*.yaml
  bool resumable = false;  ///< `train --resume` continues a killed run
  std::string no_step_hint;  ///< what to do instead of a step the kind lacks (one clause)
  /// Every key of its config with its default (config::ReferenceTable<Config>).
  std::function<std::string()> reference;
  /// Trains into request.run_dir, exports the artifact and (request.evaluate) evaluates it.
  std::function<void(const TrainRequest&)> train;
  /// Writes the run's artifact from its training state. @return the artifact path.
  std::function<std::string(const std::string& run_dir)> export_run;
  /// Evaluates the run's artifact with the run's config (+ overrides, e.g. data.root); writes
  /// run_dir/eval.json. @return its text.
  std::function<std::string(const std::string& run_dir, const std::vector<std::string>& overrides)>
      evaluate;
  /// Prints figures measured side by side in one run (medians of repeated runs); never a test.
  std::function<void(const BenchRequest&)> bench;
  /// Every bench option with its default (config::ReferenceTable<Options>), for the reference.
  std::function<std::string()> bench_reference;

  bool Matches(const std::string& model_tag) const;
  /// The one-line Error for a step (`train`, `export`, `eval`, `bench`) this kind does not have.
  [[noreturn]] void NoSuchStep(const std::string& step) const;
};

/// The kinds a build knows. Lookups that find nothing are an Error naming the source and listing
/// the known tags.
class ExperimentRegistry {
 public:
  /// Adds a kind; a tag that another kind already matches is an Error.
  void Add(ExperimentKind kind);
  /// Makes `tag`'s kind the one that `train default` runs.
  void SetDefault(const std::string& tag);

  const ExperimentKind& ForModel(const std::string& model_tag, const std::string& source) const;
  /// The kind of a config file (its top-level `model:`), or the default kind for "default".
  const ExperimentKind& ForConfig(const std::string& config) const;
  /// The kind of a run directory (the `model:` of run_dir/config.yaml).
  const ExperimentKind& ForRun(const std::string& run_dir) const;
  /// The kind of an exported artifact (the `model:` of the config stored in it).
  const ExperimentKind& ForArtifact(const std::string& artifact) const;
  /// The kind of a bench target (a directory is a run, a `.h5` file an artifact, anything else a
  /// config); sets request->what.
  const ExperimentKind& ForBenchTarget(BenchRequest* request) const;

  const std::vector<ExperimentKind>& kinds() const { return kinds_; }
  /// The config reference of every kind (docs/config_reference.md).
  std::string ReferenceMarkdown() const;

 private:
  std::string KnownTags() const;
  std::vector<ExperimentKind> kinds_;
  std::string default_tag_;
};

/// The artifact a bench times: the artifact target, or `in_run` (relative to the run directory:
/// "model.h5"; a folder "models/" means its one .h5 file, an Error listing them if there are
/// several) of a run. A config target, or config overrides, are an Error.
std::string BenchArtifact(const BenchRequest& req, const std::string& in_run);

/// The top-level `model:` of a YAML file (an Error naming the file when it has none).
std::string ModelTagOfFile(const std::string& path);

}  // namespace foresight
