#pragma once
/// Continuous spatiotemporal directional maps (thesis ch 4) through the one pipeline:
///   samples (x, y, t, theta) -> K folds -> per fold: train the spatiotemporal (and spatial)
///   network with the trainer, export, query the Eigen engine on the test fold; fit the directional
///   grid maps (UM, MM, dense variants) on the same training split -> AL and MRE per method.
///
/// Run directory:
///   config.yaml, log.txt, eval.json, eval.csv (one row per method and fold), model.h5 (the
///   spatiotemporal model of fold 0, trained on fold 0's training split; model_spatial.h5
///   likewise), folds/<k>/<spatiotemporal|spatial>/{metrics.csv, checkpoints/, model.h5,
///   training_summary.json}, plots/directions.png (mixture means over the data),
///   plots/trajectories.png (generated paths).
/// Resume continues every unfinished fold network from its last checkpoint and skips finished ones.

#include <string>
#include <utility>
#include <vector>

#include "datasets/directional.h"
#include "inference/directional/directional_map.h"
#include "models/directional/directional_net.h"
#include "training/directional/config.h"
#include "training/run_dir.h"
#include "training/trainer.h"

namespace foresight::directional {

/// Loads (or generates) the config's samples, validated; reader statistics are logged.
DirectionalSamples LoadSamples(const ExperimentConfig& config);

/// Trains one network on `train` (early stopping / best epoch on `val`) into `dir` and exports
/// dir/model.h5 from the best checkpoint. `features` must be resolved (no auto flags). An already
/// exported dir is left alone (returns a summary with reason kAlreadyComplete).
TrainingSummary TrainNet(const ExperimentConfig& config, const FeatureConfig& features,
                         Variant variant, const DirectionalSamples& train,
                         const DirectionalSamples& val, const std::string& dir, bool resume,
                         const TrainHooks& hooks = {});

/// Writes an artifact of `net` (schema: docs/artifact_schema.md, model_type directional_map).
void WriteArtifact(NetImpl& net, const FeatureConfig& features, const std::string& config_yaml,
                   std::int64_t seed, const std::string& path);

/// Rebuilds the LibTorch network of an artifact (parity tests, benchmark).
struct LoadedNet {
  Net net{nullptr};
  FeatureConfig features;
};
LoadedNet LoadNetFromArtifact(const std::string& path);

/// One method's scores on one test split: AL and MRE as the thesis defines them (every
/// concentration as the method predicts it, capped at network.max_kappa), AL again with the
/// concentrations capped at each eval.metric_caps value, and mre_w, the MRE over the components
/// weighing at least eval.mre_min_weight (so a spike of negligible weight cannot score).
struct Score {
  double al = 0, mre = 0, mre_w = 0;
  std::vector<double> al_caps;  ///< [metric_caps]
};

struct MethodMetrics {
  std::string method;
  std::vector<double> al, mre;               ///< per fold
  std::vector<double> mre_w;                 ///< per fold
  std::vector<std::vector<double>> al_caps;  ///< [cap][fold]
  double MeanAl() const;
  double MeanMre() const;
  double StdAl() const;
  double StdMre() const;
};

struct EvalReport {
  Eigen::Index samples = 0;
  int folds = 0, folds_evaluated = 0;
  std::string folds_by;             ///< "path" or "point"
  std::vector<double> metric_caps;  ///< of al_caps
  FeatureConfig features;           ///< resolved
  std::vector<MethodMetrics> methods;
  const MethodMetrics* Find(const std::string& method) const;
  /// `{ "spatiotemporal": {"al": .., "mre": .., "al_std": .., "mre_std": .., "al_folds": [..],
  /// "mre_folds": [..], "mre_w": .., "al_cap10": .., ...}, ..., "samples": n, "folds": K,
  /// "folds_by": "path", "folds_evaluated": k, "resolution": {..} }`
  std::string ToJson() const;
  std::string ToCsv() const;
  std::string BriefReport() const;
};

struct RunResult {
  EvalReport report;
  TrainingSummary last;  ///< of the last trained network
  bool interrupted = false;
};

/// What shows a directional run in a directory (resume continues unfinished fold networks).
inline const RunDirectoryRules kDirectionalRunRules{{"folds", "model.h5", "eval.json"}, true};

/// The whole experiment into `run_dir` (see above). A fresh start refuses a directory that holds
/// an earlier run. Empty or non-finite data is an Error naming the source.
RunResult RunExperiment(const ExperimentConfig& config, const std::string& run_dir, bool resume,
                        const TrainHooks& hooks = {});

/// Evaluates a finished run again (every fold network exists; an Error names the first missing
/// one) with `config`, which may differ from the run's in where the data is (data.root): writes
/// eval.json, eval.csv and the plots; trains nothing and does not touch config.yaml.
EvalReport EvaluateRun(const ExperimentConfig& config, const std::string& run_dir);

/// Rewrites every fold network's model.h5 from its best checkpoint and the run's model.h5 (fold 0).
/// A fold without a checkpoint is an Error naming it. @return the run's artifact path.
std::string ExportRun(const std::string& run_dir);

/// Evaluates the methods on one split: returns the scores of spatiotemporal, spatial (optional),
/// grid_um, grid_mm (+ dense), nn1 and knn (nearest training headings at max_kappa; with time as
/// a coordinate when the features have more than one time point). Networks are trained into
/// `work_dir`/<variant>.
std::vector<std::pair<std::string, Score>> EvaluateSplit(
    const ExperimentConfig& config, const FeatureConfig& features, const DirectionalSamples& train,
    const DirectionalSamples& test, const std::string& work_dir, const TrainHooks& hooks = {},
    bool* interrupted = nullptr);

}  // namespace foresight::directional
