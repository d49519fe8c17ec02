#pragma once
/// Evaluation of a constrained-prediction run (thesis ch 7, tables "tableRes1" and "tableRes2"):
/// every test window is predicted by the prior (mixture of matrix normals), projected onto the
/// chance constraint C <= epsilon on its scene's fitted map, and scored against the truth together
/// with the baselines (KTM, constant velocity, naive network) by one metrics module
/// (inference/constrained/prediction_metrics.h). Torch-free: engines only.
///
/// eval.json: windows and data counts; `prior`, `optimised` (ade/fde of the nearest component, of
/// the mixture mean, al, anll, cvp) over all test windows and over the prior-violating ones; `ktm`,
/// `cv`, `naive`; solve statuses and time percentiles (one core); the quadrature accuracy of C
/// against Monte Carlo and against a high-order rule. tracks.csv: one row per test window.

#include <atomic>
#include <string>

#include "training/constrained/config.h"
#include "training/constrained/data.h"

namespace foresight::constrained {

/// The artifacts of a run directory (written by training).
struct RunArtifacts {
  std::string prior, ktm, naive;  ///< empty when the baseline is disabled
  std::string maps_dir;           ///< fitted maps: <maps_dir>/<scene>.h5 (SceneMapFile)
};
RunArtifacts ArtifactsOf(const ExperimentConfig& c, const std::string& run_dir);

/// Fits the occupancy map of every scene in `scenes` whose artifact is missing (run_dir/maps/).
/// @return false when `interrupt` was set between two scenes (the maps written so far are kept).
bool FitSceneMaps(const ExperimentConfig& c, const std::vector<MapScene>& scenes,
                  const std::string& run_dir, const std::atomic<bool>* interrupt = nullptr);

/// Evaluates; writes `run_dir`/eval.json, tracks.csv and plots/ (when eval.plot_windows > 0).
/// Missing artifacts are Errors naming them. @return the eval.json text.
std::string EvaluateConstrained(const ExperimentConfig& c, const ConstrainedData& d,
                                const std::string& run_dir);

}  // namespace foresight::constrained
