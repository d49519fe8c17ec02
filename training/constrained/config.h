#pragma once
/// The config of a structurally constrained prediction run (thesis ch 7), `foresight train
/// configs/constrained/<dataset>.yaml`: scenes with maps, the split, the observation/prediction
/// windows, the occupancy map fitted to each scene's obstacles, the mixture-of-matrix-normals prior
/// and its training, the KTM and naive baselines, the chance constraint and its solver, and the
/// evaluation. Torch-free.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/map_tracks.h"
#include "datasets/windows.h"
#include "inference/constrained/collision_cost.h"
#include "models/occupancy/raster_map.h"
#include "models/span/span_config.h"
#include "training/train_config.h"

namespace foresight::constrained {

struct SplitConfig {
  bool by_scene = false;       ///< whole scenes (map-level) or tracks within each scene
  double val_fraction = 0.1;   ///< validation share (model selection; never the test)
  double test_fraction = 0.2;  ///< test share (thesis: 80:20)

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("by_scene", &by_scene, Range::Any(),
             "split whole scenes (map-level: occ_traj, synthetic) or tracks within each scene");
    a->Visit("val_fraction", &val_fraction, Range::Closed(0, 0.9), "validation share");
    a->Visit("test_fraction", &test_fraction, Range::Closed(0.01, 0.9), "test share");
  }
};

struct MapConfig {
  occupancy::RasterMapKind kind = occupancy::RasterMapKind::kFastBhm;
  double sample_step = 0.1;  ///< labelled points every this many m (cells for occ_traj)
  double spacing = 0.25;     ///< Fast-BHM inducing-point spacing
  double margin = 1.0;       ///< the map covers the raster grown by this much

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->VisitEnum("kind", &kind,
                 config::EnumNames<occupancy::RasterMapKind>{
                     {occupancy::RasterMapKind::kFastBhm, "fast_bhm"},
                     {occupancy::RasterMapKind::kGrid, "grid"}},
                 "occupancy map fitted to each scene's obstacle raster (p(m=1|x) and gradient)");
    a->Visit("sample_step", &sample_step, Range::Closed(0.01, 10.0),
             "labelled raster points every this many m (cells for occ_traj)");
    a->Visit("spacing", &spacing, Range::Closed(0.02, 10.0),
             "Fast-BHM inducing-point spacing (gamma scales as spacing^-2)");
    a->Visit("margin", &margin, Range::Closed(0, 20.0), "the map covers the raster grown by this");
  }
  occupancy::RasterMapOptions Options() const { return {kind, sample_step, spacing, margin}; }
};

struct KtmConfig {
  bool enabled = true;
  int references = 100;      ///< reference segments from the training windows
  double lengthscale = 1.0;  ///< kernel length-scale of the RMS segment distance (m)

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("enabled", &enabled, Range::Any(), "train and evaluate the KTM baseline");
    a->Visit("references", &references, Range::Closed(2, 5000), "KTM reference segments");
    a->Visit("lengthscale", &lengthscale, Range::Positive(),
             "KTM kernel length-scale (m) of the RMS distance between segments");
  }
};

struct NaiveConfig {
  bool enabled = true;
  std::vector<int> hidden = {560, 180, 180};  ///< thesis: 560-180-180-N_t, ReLU, MSE

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("enabled", &enabled, Range::Any(), "train and evaluate the naive network");
    a->Visit("hidden", &hidden, Range::Closed(1, 4096), "hidden widths (thesis 560, 180, 180)");
  }
};

struct ConstraintConfig {
  double epsilon = 0.05;  ///< C <= epsilon is compliant (thesis 0.05)
  double margin = 2e-4;   ///< solve to epsilon - margin so the returned C is truly <= epsilon
  int order = 6;          ///< Gauss-Hermite points per axis
  int substeps = 1;       ///< rectangle-rule time points per prediction step
  TimeRule time_rule =
      TimeRule::kRight;  ///< where the rectangle rule's points sit in each interval
  /// Choose order and substeps on validation windows: the cheapest (order^2 x substeps) candidate
  /// whose C is within `accuracy` of the converged C on every one of `choice_windows` priors.
  bool choose_quadrature = false;
  double accuracy = 1e-3;
  int choice_windows = 40;
  int check_order = 0;  ///< verify every result with this Gauss-Hermite order (0: no check)
  /// With choose_quadrature: choose check_order and check_substeps on projected validation
  /// windows the same way (within `check_accuracy` of the converged C).
  bool choose_check = false;
  double check_accuracy = 1e-3;  ///< the chosen check's largest error on the projected windows
  int check_substeps = 4;        ///< midpoints per prediction step of the check operator
  int check_rounds = 3;          ///< repeated solves with a lowered target when the check fails
  int restarts = 2;  ///< SLSQP restarts from the lowest-cost point when no feasible one was found
  bool feasibility_phase = true;  ///< then minimise C alone and restart SLSQP from a feasible point
  int max_evaluations = 300;      ///< SLSQP objective evaluations per component
  double max_seconds = 1.0;       ///< wall-time limit per component (s)

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("epsilon", &epsilon, Range::Open(0, 1), "allowed time-averaged collision probability");
    a->Visit("margin", &margin, Range::Closed(0, 0.01),
             "the solver aims at epsilon - margin (its tolerance must not count as compliance)");
    a->Visit("order", &order, Range::Closed(1, 40), "Gauss-Hermite points per axis");
    a->Visit("substeps", &substeps, Range::Closed(1, 64),
             "time points of the rectangle rule per prediction step (1: at the predicted steps)");
    a->VisitEnum(
        "time_rule", &time_rule,
        config::EnumNames<TimeRule>{{TimeRule::kRight, "right"}, {TimeRule::kMidpoint, "midpoint"}},
        "rectangle-rule points at the right end (thesis: the predicted steps) or the "
        "middle of each time interval (second order)");
    a->Visit("choose_quadrature", &choose_quadrature, Range::Any(),
             "choose order and substeps on validation windows (overrides both; see accuracy)");
    a->Visit("accuracy", &accuracy, Range::Open(0, 1),
             "largest |C - converged C| allowed on the validation priors when choosing");
    a->Visit("choice_windows", &choice_windows, Range::Closed(1, 100000),
             "validation windows (evenly spread) the quadrature choice is made on");
    a->Visit("check_order", &check_order, Range::Closed(0, 64),
             "verify each result with this Gauss-Hermite order; a result it finds above epsilon "
             "is solved again (docs/constrained.md, the check operator; 0: no check)");
    a->Visit("choose_check", &choose_check, Range::Any(),
             "with choose_quadrature: choose check_order and check_substeps on the projected "
             "validation windows (overrides both)");
    a->Visit("check_accuracy", &check_accuracy, Range::Open(0, 1),
             "with choose_check: the largest |C - converged C| allowed of the check on the "
             "projected validation windows; the check then accepts C <= epsilon - its error");
    a->Visit("check_substeps", &check_substeps, Range::Closed(1, 64),
             "midpoint time points per prediction step of the check operator");
    a->Visit("check_rounds", &check_rounds, Range::Closed(0, 20),
             "repeated solves at most when the check finds the result above epsilon");
    a->Visit("restarts", &restarts, Range::Closed(0, 100),
             "SLSQP restarts from the lowest-cost point seen when it stops infeasible");
    a->Visit("feasibility_phase", &feasibility_phase, Range::Any(),
             "when SLSQP and its restarts find no feasible point: minimise C alone (L-BFGS) until "
             "it is met, then SLSQP from there");
    a->Visit("max_evaluations", &max_evaluations, Range::Closed(1, 100000),
             "SLSQP evaluations per component at most");
    a->Visit("max_seconds", &max_seconds, Range::Closed(0, 3600),
             "wall-time limit per component (s, 0: none)");
  }
};

struct EvalConfig {
  int max_windows = 0;           ///< evaluate at most this many test windows (0: all)
  int accuracy_windows = 20;     ///< windows whose C is checked against Monte Carlo
  int accuracy_samples = 20000;  ///< Monte Carlo samples per component and window
  int plot_windows = 4;          ///< violating windows drawn in plots/ (0: none)
  int plot_samples = 30;         ///< sampled trajectories per distribution in the plots
  std::int64_t sample_seed = 7;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("max_windows", &max_windows, Range::AtLeast(0), "cap on test windows (0: all)");
    a->Visit("accuracy_windows", &accuracy_windows, Range::Closed(0, 10000),
             "windows whose quadrature C is compared with Monte Carlo");
    a->Visit("accuracy_samples", &accuracy_samples, Range::Closed(100, 10000000),
             "Monte Carlo samples per component and window");
    a->Visit("plot_windows", &plot_windows, Range::Closed(0, 64),
             "violating windows drawn (prior vs optimised)");
    a->Visit("plot_samples", &plot_samples, Range::Closed(0, 1000),
             "sampled trajectories per distribution in the plots");
    a->Visit("sample_seed", &sample_seed, Range::Any(), "seed of sampling in eval and plots");
  }
};

struct ExperimentConfig {
  std::string model = "constrained";
  std::int64_t seed = 0;
  MapTracksConfig data;
  SplitConfig split;
  WindowConfig windows{10, 15, 1};
  MapConfig map;
  span::TrajectoryBasisConfig basis;
  span::NetConfig network;
  TrainConfig train;
  KtmConfig ktm;
  NaiveConfig naive;
  ConstraintConfig constraint;
  EvalConfig eval;

  ExperimentConfig() {
    network.components = 2;  // thesis: R = 2
    network.u_param = UParam::kDiagonal;
  }

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("model", &model, Range::Any(), "model type (constrained)");
    a->Visit("seed", &seed, Range::Any(), "seed of splits, initialisation and shuffling");
    a->Visit("data", &data, Range::Any(), "scenes: tracks and their obstacle maps");
    a->Visit("split", &split, Range::Any(), "train / validation / test split");
    a->Visit("windows", &windows, Range::Any(), "observed / predicted points (thesis: 10 / T)");
    a->Visit("map", &map, Range::Any(), "occupancy map fitted to each scene");
    a->Visit("basis", &basis, Range::Any(), "RBF trajectory basis of the futures");
    a->Visit("network", &network, Range::Any(),
             "prior network and mixture head (u_param must be diagonal)");
    a->Visit("train", &train, Range::Any(), "trainer (prior, KTM and naive networks)");
    a->Visit("ktm", &ktm, Range::Any(), "Kernel Trajectory Maps baseline");
    a->Visit("naive", &naive, Range::Any(), "naive network baseline");
    a->Visit("constraint", &constraint, Range::Any(), "chance constraint and its SLSQP solve");
    a->Visit("eval", &eval, Range::Any(), "evaluation");
  }
  /// Rules across keys; errors name `source` and the key.
  void Validate(const std::string& source) const;
};

}  // namespace foresight::constrained
