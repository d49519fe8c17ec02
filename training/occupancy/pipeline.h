#pragma once
/// Occupancy-map runs: scans -> labelled points and splits -> a map (Fast-BHM, BHM, Hilbert map,
/// grid, or the multi-robot fusion experiment) -> one artifact -> evaluation on held-out scans.
/// Torch-free; `foresight train` dispatches here when the config's model is occupancy.*.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/binary_metrics.h"
#include "datasets/laser_scan.h"
#include "datasets/occupancy_points.h"
#include "inference/mapping/occupancy_map.h"
#include "training/occupancy/config.h"
#include "training/run_dir.h"

namespace foresight::occupancy {

struct BoundUpdateReport;  // models/occupancy/coupled_bhm.h

/// Scans and labelled points of an experiment, split by scan.
struct Data {
  std::vector<LaserScan> scans;  ///< all scans, in recording order
  LabelledPoints points;         ///< labelled points of all scans (scan s of points = scans[s])
  std::vector<int> train_scans, val_scans, test_scans;  ///< indices into scans, in order
  LabelledPoints train, val, test;                      ///< points of those scans
  std::vector<LaserScan> TrainScanList() const;         ///< the training scans themselves
};

/// Reads or simulates the scans and splits them (test: every test_every-th scan; training: the
/// rest, thinned by train_scan_stride, minus every val_every-th for validation).
Data LoadData(const ExperimentConfig& config);

/// Trains one map of kind `model` (occupancy.fast_bhm | bhm | hilbert | grid) on the training
/// scans, in recording order. `seconds` receives the wall-clock training time; `bound_reports`
/// the ELBO of every bound update (fast_bhm.update: coupled; also for bhm, whose coupled variant
/// keeps the learned posterior with its dense covariance).
std::unique_ptr<Map> TrainMap(const std::string& model, const ExperimentConfig& config,
                              const Data& data, double* seconds = nullptr,
                              std::vector<BoundUpdateReport>* bound_reports = nullptr);
/// Writes the map's artifact (hinge maps with config.precision).
void SaveMap(const Map& map, const std::string& path, const ExperimentConfig& config);
/// Size in bytes of the artifact SaveOccupancyMap would write (measured via a temporary file).
std::int64_t ArtifactBytes(const Map& map, const ExperimentConfig& config);
/// AUC, precision and recall (threshold 0.5) of the map's probabilities on labelled points.
BinaryMetrics EvaluateMap(const Map& map, const LabelledPoints& points);

/// Multi-robot fusion (thesis ch 3 "Fusion of Fast-BHM"): single map, fuse once, repeated fusion.
/// fast_bhm.update: coupled -> single, fuse_once (the robots' sparse information summed: exact
/// for their bounds) and conflated (their diagonal maps conflated: approximate); published ->
/// single, fuse_once and repeated (conflation, the thesis's algorithms).
struct FusionResult {
  std::unique_ptr<Map> single, fuse_once, repeated, conflated;
  std::vector<int> robot_scans;                 ///< training scans per robot
  std::vector<std::int64_t> information_bytes;  ///< coupled: per robot, of its sparse information
};
FusionResult RunFusion(const ExperimentConfig& config, const Data& data);

/// What shows an occupancy run in a directory (maps train in one pass: no resume).
inline const RunDirectoryRules kOccupancyRunRules{{"model.h5", "eval.json"}, false};

/// Trains the map (or the fusion experiment) into RUN_DIR: model.h5 (the fused map for
/// occupancy.fusion, with single.h5 and fuse_once.h5), training_summary.json (seconds).
void TrainRun(const ExperimentConfig& config, const std::string& run_dir);

/// Evaluates the run's maps as loaded from their artifacts on the held-out scans: writes
/// eval.json, roc.csv (single maps) and plots/map.png. @return the eval.json text.
std::string EvaluateRun(const ExperimentConfig& config, const std::string& run_dir);

}  // namespace foresight::occupancy
