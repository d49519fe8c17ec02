#pragma once
/// The config of a diffeomorphic-templates run (thesis ch 8): the demonstrations (LASA shapes, a
/// synthetic family, or task-space demonstrations for the JACO arm), the imitation flow and its
/// training, the Euclideanizing-Flows baseline, the obstacle placed on the demonstrations, the
/// user bias and the evaluation. `foresight train configs/diffeo/<name>.yaml`. Torch-free.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "training/train_config.h"

namespace foresight::imitation {

enum class DemoSource { kLasa, kSynthetic, kTaskSpace };

/// Where the demonstrations come from and how they are prepared.
struct DataConfig {
  DemoSource source = DemoSource::kSynthetic;
  std::string
      root;  ///< data root (lasa: <root>/lasa_handwriting); empty: $FORESIGHT_DATA, ../shared/data
  std::vector<std::string> shapes{"all"};   ///< lasa: shape names, or "all" (every CSV found)
  std::string synthetic_shape = "s_curve";  ///< synthetic: the curve family
  int synthetic_demos = 7;
  int synthetic_points = 200;
  double synthetic_noise = 0.05;
  std::string task = "push_box";    ///< task_space: push_box | lift_box
  int task_demos = 7;               ///< thesis: 7 (push box), 8 (lift box)
  int downsample = 4;               ///< keep every n-th sample (LASA has 1000 per demo)
  std::vector<int> held_out{5, 6};  ///< demo indices not trained on (evaluated from their starts)
  /// Demo indices dropped before anything reads them: a validation run leaves the test demos
  /// (held_out of the report run) out entirely and holds out one of the rest instead.
  std::vector<int> excluded;
  double goal_tolerance = 0.02;  ///< refuse demos whose final points spread more than this x extent
  double half_range = 0.5;       ///< positions normalised into [-half_range, half_range]

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->VisitEnum("source", &source,
                 config::EnumNames<DemoSource>{{DemoSource::kLasa, "lasa"},
                                               {DemoSource::kSynthetic, "synthetic"},
                                               {DemoSource::kTaskSpace, "task_space"}},
                 "lasa (../shared/data/lasa_handwriting), synthetic 2-D, or task_space (JACO)");
    a->Visit("root", &root, Range::Any(), "data root; empty: $FORESIGHT_DATA, else ../shared/data");
    a->Visit("shapes", &shapes, Range::Any(), "lasa shapes, or [all]");
    a->Visit("synthetic_shape", &synthetic_shape, Range::Any(),
             "synthetic curve family (s_curve, arc, zigzag)");
    a->Visit("synthetic_demos", &synthetic_demos, Range::Closed(2, 1000), "synthetic demos");
    a->Visit("synthetic_points", &synthetic_points, Range::Closed(10, 100000),
             "points per synthetic demo");
    a->Visit("synthetic_noise", &synthetic_noise, Range::Closed(0, 1),
             "perturbation of the synthetic demos (share of the extent)");
    a->Visit("task", &task, Range::Any(), "task_space task: push_box | lift_box");
    a->Visit("task_demos", &task_demos, Range::Closed(2, 1000), "task-space demos");
    a->Visit("downsample", &downsample, Range::Closed(1, 1000), "keep every n-th sample");
    a->Visit("held_out", &held_out, Range::Any(), "demo indices held out of training");
    a->Visit("excluded", &excluded, Range::Any(),
             "demo indices never read (validation runs exclude the test demos)");
    a->Visit("goal_tolerance", &goal_tolerance, Range::Closed(0, 1),
             "largest spread of the demos' final points, as a share of their extent");
    a->Visit("half_range", &half_range, Range::Positive(),
             "normalised positions lie in [-half_range, half_range]");
  }
};

/// Another flow time and Euler step count a shape's flow may be trained with (flow.alternatives).
struct FlowAlternative {
  double time = 2.0;  ///< flow time T
  int steps = 20;     ///< Euler steps K

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("time", &time, Range::Positive(), "flow time T of this alternative");
    a->Visit("steps", &steps, Range::Closed(1, 10000), "Euler steps K of this alternative");
  }
};

/// The imitation transform psi_i: RBF field on a grid of inducing states, integrated by Euler.
struct FlowConfig {
  // Defaults: 19 x 19 = 361 states over [-0.65, 0.65]^2 (thesis: 720; wider kernels gave lower
  // Frechet distances on the synthetic family); gamma * cutoff^2 = 18, so the truncated kernel is
  // 1.5e-8 at the cut-off and the Euler map stays exactly invertible.
  double spacing = 0.07;            ///< inducing-state spacing (normalised units)
  double margin = 0.15;             ///< grid margin around the demonstrations
  double gamma = 100;               ///< kernel exp(-gamma d^2)
  double cutoff_radius = 0.425;     ///< features beyond this are zero
  double time = 1.0;                ///< flow time T
  int steps = 10;                   ///< Euler steps K
  int segments = 1;                 ///< time segments S (1: one stationary field, the thesis)
  double inverse_tolerance = 1e-9;  ///< refuse a flow whose psi^-1(psi(x)) misses x by more
                                    ///< (plus the truncation allowance LoadTemplate grants)
  /// Weight of the training penalty that keeps every Euler step contracting (h ||DV|| < 0.7) on the
  /// batch and on a lattice of `penalty_lattice` points per axis over the grid's box.
  double invertibility_weight = 10;
  int penalty_lattice = 12;
  /// Tube samples (ours only; 0 = off): `tube_copies` copies of every training pair with the
  /// position moved by N(0, tube_sigma^2 I) and the velocity v - tube_gain * offset, so the field
  /// is taught near the demonstrations too (rollouts that drift off them are led back).
  double tube_sigma = 0;
  int tube_copies = 4;
  double tube_gain = 0;
  /// Train through LibTorch autograd instead of the hand-written sparse objective
  /// (models/imitation/flow_objective.h: the same loss and gradient to rounding, faster).
  bool autograd = false;
  /// Flows trained per shape (each with its own seed: tube samples, validation split, batch
  /// order); the one exported is chosen on the training demonstrations (train.h, ExportShape).
  int restarts = 1;
  /// Other (time, steps) settings, each trained with the same `restarts` seeds; the restart
  /// exported is chosen among all of them by the same training-demo criterion, so each shape gets
  /// the flow length that follows its training demos best. Empty: `time` and `steps` only.
  std::vector<FlowAlternative> alternatives;

  /// Flows trained per shape: restarts x (1 + alternatives).
  int TotalRestarts() const { return restarts * (1 + static_cast<int>(alternatives.size())); }

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("spacing", &spacing, Range::Positive(), "distance between inducing states");
    a->Visit("margin", &margin, Range::NonNegative(), "grid margin around the demonstrations");
    a->Visit("gamma", &gamma, Range::Positive(), "Gaussian RBF exp(-gamma d^2)");
    a->Visit("cutoff_radius", &cutoff_radius, Range::Positive(), "RBF cut-off radius");
    a->Visit("time", &time, Range::Positive(), "flow time T");
    a->Visit("steps", &steps, Range::Closed(1, 10000), "Euler steps K");
    a->Visit("segments", &segments, Range::Closed(1, 10000),
             "time segments S <= K, each with its own RBF weights (1: one stationary field)");
    a->Visit("inverse_tolerance", &inverse_tolerance, Range::Positive(),
             "largest round-trip error psi^-1(psi(x)) - x accepted at export, on top of the "
             "truncation allowance 10 T discontinuity (as at load)");
    a->Visit("invertibility_weight", &invertibility_weight, Range::NonNegative(),
             "weight of the penalty keeping each Euler step contracting (0: off)");
    a->Visit("penalty_lattice", &penalty_lattice, Range::Closed(2, 100),
             "points per axis of the penalty lattice over the grid's box");
    a->Visit("tube_sigma", &tube_sigma, Range::NonNegative(),
             "std of the position offsets of the tube samples (normalised units; 0: none)");
    a->Visit("tube_copies", &tube_copies, Range::Closed(1, 100), "tube samples per training pair");
    a->Visit("tube_gain", &tube_gain, Range::NonNegative(),
             "tube samples' velocity v - gain * offset (1/s; 0: parallel to the demo)");
    a->Visit("autograd", &autograd, Range::Any(),
             "train by LibTorch autograd through the integration instead of the hand-written "
             "sparse loss and gradient (the same to rounding; slower; a cross-check)");
    a->Visit("restarts", &restarts, Range::Closed(1, 100),
             "flows trained per shape (per setting, with flow.alternatives) with seeds seed + "
             "1000 k, k < restarts; exported: the invertible one whose rollouts from the training "
             "starts follow the training demos best (mean Frechet)");
    a->Visit("alternatives", &alternatives, Range::Any(),
             "other {time, steps} of the flow, each trained with the same restarts; the export "
             "chooses among all of them by the same training-demo criterion (empty: none)");
  }
};

/// Euclideanizing Flows (Rana et al. 2020), the baseline, trained the same way.
struct EflowConfig {
  bool enabled = true;
  // Defaults of the authors' implementation on the same [-0.5, 0.5] normalisation: 10 layers,
  // 200 features, length scale 0.45 (bandwidth 1 / 0.45).
  int layers = 10;
  int features = 200;         ///< random Fourier features per coupling layer
  double bandwidth = 2.2222;  ///< std of the random frequencies
  TrainConfig train = [] {
    TrainConfig t;
    t.epochs = 600;
    t.batch_size = 128;
    t.learning_rate = 1e-3;
    t.patience = 100;
    t.progress = ProgressStyle::kNone;
    return t;
  }();

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("enabled", &enabled, Range::Any(), "train and evaluate the baseline");
    a->Visit("layers", &layers, Range::Closed(1, 100), "coupling layers");
    a->Visit("features", &features, Range::Closed(1, 10000), "random Fourier features per layer");
    a->Visit("bandwidth", &bandwidth, Range::Positive(), "std of the random frequencies");
    a->Visit("train", &train, Range::Any(), "trainer settings of the baseline");
  }
};

/// The obstacle placed on the demonstrations, its occupancy map and the avoidance transforms.
struct ObstacleConfig {
  bool enabled = true;
  double fraction = 0.5;  ///< centre: the first training demo's point at this share of its length
  /// Radius: 2-D in normalised units; task space in metres (thesis: a 15 cm diameter cylinder).
  double radius = 0.06;
  double height = 0.4;  ///< task space: cylinder height (m), standing on z = 0
  // The occupancy map (Hilbert map on RBF features) trained on samples of the obstacle.
  // A soft map (kernel width ~ the obstacle's radius, strong ridge): its gradient reaches across
  // the obstacle, so the flow can push whole paths out; gamma * cutoff^2 = 18 keeps the truncated
  // kernel at 1.5e-8 (a smooth, invertible flow).
  double map_spacing = 0.06;  ///< inducing-state spacing of the map
  double map_gamma = 200;     ///< its kernel exp(-gamma d^2)
  double map_cutoff = 0.3;    ///< its cut-off
  double map_l2 = 1;          ///< ridge penalty of the logistic regression
  /// 2-D: > 0 evaluates the fitted map through a bicubic Hermite table of its logit with nodes
  /// this far apart (OccupancyField::Tabulate; selection, rollouts and metrics all use it); 0: the
  /// exact feature sums. Task space does not read it.
  double map_table_spacing = 0;
  double map_inflate = 0.01;     ///< samples within this distance of the obstacle are occupied
  double sample_spacing = 0.01;  ///< occupancy samples on a lattice around the obstacle
  double sample_margin = 0.1;    ///< lattice margin around the obstacle
  /// Obstacle-flow times tried, smallest first, up to the first whose Euler map is not invertible
  /// (checked on the sample lattice or along the rollouts): the first whose rollouts from the
  /// training starts keep the map's p(occupied) below `clear_probability` is used (2-D with
  /// `select_on_grid`: of those, the first with the fewest grid crossings). Selection on the map,
  /// not on the exact obstacle the metrics use.
  std::vector<double> times{0.002, 0.004, 0.008, 0.016, 0.032, 0.064};
  double step = 0.0005;  ///< Euler step of the obstacle flow (steps = ceil(time / step))
  /// The Euler step is also at most step_lipschitz / L, L the largest |Hess p| measured on a
  /// lattice around the obstacle (2-D) or |dV_q| along the plain rollouts (C-space): h L < 1 keeps
  /// every step of the map invertible where L bounds the field's slope.
  double step_lipschitz = 0.5;
  /// Task space: a flow time whose Euler map does not invert along the rollouts is tried again
  /// with the step halved, up to this many times in total over all times (a halved step is kept
  /// for the larger ones), before it is given up (the coarsest step that
  /// inverts: fewer Euler steps, a cheaper rollout step). 0: one step size (2-D does not read it).
  int step_halvings = 0;
  double clear_probability = 0.5;
  /// 2-D: the selection also rolls out from a grid of starts (`eval.grid` per axis over the
  /// training demos' box, those the map calls free): among the settings whose training starts are
  /// clear, the first with the fewest grid rollouts crossing the map (p >= clear_probability) is
  /// used, so the setting clears as much of the space around the demonstrations as it can, not
  /// only the training starts. No held-out demonstration enters. (Task space does not read it.)
  bool select_on_grid = true;
  /// Largest round-trip error psi_o^-1(psi_o(y)) - y accepted when checking a flow time
  /// (normalised units in 2-D, rad in C-space); every inverse must also converge.
  double inverse_tolerance = 1e-8;
  /// The obstacle field fades out within about this distance of the goal (2-D: normalised units,
  /// ObstacleGate in transforms.h; task space: m, the C-space goal gate in cspace.h), so psi_o
  /// fixes the goal and the rollouts still reach it; 0 = no gate.
  double goal_gate = 0;
  std::vector<double> repulsor_gains{0.01, 0.03, 0.1, 0.3, 1, 3};  ///< EFlow + repulsor, likewise

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("enabled", &enabled, Range::Any(), "place an obstacle and evaluate avoidance");
    a->Visit("fraction", &fraction, Range::Closed(0, 1),
             "obstacle centre along the first training demonstration (share of arc length)");
    a->Visit("radius", &radius, Range::Positive(),
             "obstacle radius (2-D normalised units; task m)");
    a->Visit("height", &height, Range::Positive(), "task space: cylinder height (m)");
    a->Visit("map_spacing", &map_spacing, Range::Positive(), "occupancy map inducing spacing");
    a->Visit("map_gamma", &map_gamma, Range::Positive(), "occupancy map kernel");
    a->Visit("map_cutoff", &map_cutoff, Range::Positive(), "occupancy map cut-off");
    a->Visit("map_l2", &map_l2, Range::Positive(), "occupancy map ridge penalty");
    a->Visit("map_table_spacing", &map_table_spacing, Range::NonNegative(),
             "2-D: node spacing of a bicubic table the map is evaluated through (0: exact sums)");
    a->Visit("map_inflate", &map_inflate, Range::NonNegative(),
             "samples this close to the obstacle are labelled occupied (safety margin)");
    a->Visit("sample_spacing", &sample_spacing, Range::Positive(), "occupancy sample lattice");
    a->Visit("sample_margin", &sample_margin, Range::NonNegative(), "sample lattice margin");
    a->Visit("times", &times, Range::Any(), "obstacle-flow times tried, smallest first");
    a->Visit("step", &step, Range::Positive(), "obstacle-flow Euler step (steps = time / step)");
    a->Visit("step_lipschitz", &step_lipschitz, Range::Open(0, 1),
             "obstacle-flow Euler step at most this over the field's largest measured slope");
    a->Visit("step_halvings", &step_halvings, Range::Closed(0, 10),
             "task space: halve the obstacle-flow step up to this many times in total when a "
             "flow time's Euler map does not invert along the rollouts");
    a->Visit("clear_probability", &clear_probability, Range::Closed(0.01, 0.99),
             "rollouts must keep the map's p(occupied) below this");
    a->Visit("select_on_grid", &select_on_grid, Range::Any(),
             "2-D: among obstacle-flow times (and EFlow repulsor gains) whose training starts are "
             "clear, take the first with the fewest stability-grid rollouts crossing the map");
    a->Visit("inverse_tolerance", &inverse_tolerance, Range::Positive(),
             "largest obstacle-flow round-trip error accepted (2-D normalised units; C-space rad)");
    a->Visit("goal_gate", &goal_gate, Range::NonNegative(),
             "length within which the obstacle field fades out at the goal (2-D normalised "
             "units; task space m; 0: no gate)");
    a->Visit("repulsor_gains", &repulsor_gains, Range::Any(), "EFlow repulsor gains tried");
  }
};

/// A user bias toward a point (thesis "Infinitesimal Generators for User-Specified Bias").
struct BiasConfig {
  bool enabled = false;
  std::vector<double> target;  ///< the point (normalised units), dimension of the demos
  double region = 0.25;        ///< samples within this distance of the target
  double time = 0.05;
  int steps = 10;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("enabled", &enabled, Range::Any(), "evaluate a bias transform");
    a->Visit("target", &target, Range::Any(), "the point to bias toward (normalised units)");
    a->Visit("region", &region, Range::Positive(), "radius of the region the bias acts in");
    a->Visit("time", &time, Range::Positive(), "bias flow time");
    a->Visit("steps", &steps, Range::Closed(1, 10000), "bias flow Euler steps");
  }
};

struct EvalConfig {
  double dt = 0.01;  ///< rollout step (s, normalised time of the fitted system)
  int max_steps = 4000;
  double goal_tolerance = 0.01;    ///< normalised units
  double max_step_length = 0.005;  ///< rollout step length cap (normalised units)
  double max_joint_step = 0.02;    ///< C-space rollouts: joint step cap (rad)
  int resample = 100;              ///< arc-length points of each path for the Frechet distance
  int grid = 6;                    ///< grid x grid starts (x grid in 3-D) for the stability check
  bool plots = true;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("dt", &dt, Range::Positive(), "rollout Euler step");
    a->Visit("max_steps", &max_steps, Range::Closed(1, 10000000), "rollout step limit");
    a->Visit("goal_tolerance", &goal_tolerance, Range::Positive(),
             "a rollout reaches the goal within this distance (normalised units)");
    a->Visit("max_step_length", &max_step_length, Range::Positive(),
             "rollouts: largest step length (normalised units); steeper steps are shortened");
    a->Visit("max_joint_step", &max_joint_step, Range::Positive(),
             "C-space rollouts: largest joint step (rad)");
    a->Visit("resample", &resample, Range::Closed(2, 100000),
             "arc-length samples per path for the Frechet distance");
    a->Visit("grid", &grid, Range::Closed(2, 100), "starts per axis of the stability grid");
    a->Visit("plots", &plots, Range::Any(), "write the vector-field PNGs");
  }
};

struct ExperimentConfig {
  std::string model = "diffeo";
  std::int64_t seed = 1;
  DataConfig data;
  FlowConfig flow;
  TrainConfig train = [] {
    TrainConfig t;
    t.epochs = 300;
    t.batch_size = 128;
    t.learning_rate = 5e-3;
    t.patience = 50;
    t.progress = ProgressStyle::kNone;
    return t;
  }();
  double val_fraction = 0.15;  ///< share of the training samples that stop training early
  EflowConfig eflow;
  ObstacleConfig obstacle;
  BiasConfig bias;
  EvalConfig eval;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("model", &model, Range::Any(), "experiment type (diffeo)");
    a->Visit("seed", &seed, Range::Any(),
             "seed of the networks, the splits and the synthetic data");
    a->Visit("data", &data, Range::Any(), "demonstrations");
    a->Visit("flow", &flow, Range::Any(), "the imitation transform");
    a->Visit("train", &train, Range::Any(), "trainer settings of the imitation transform");
    a->Visit("val_fraction", &val_fraction, Range::Closed(0, 0.9),
             "share of the training samples used to stop early");
    a->Visit("eflow", &eflow, Range::Any(), "Euclideanizing-Flows baseline");
    a->Visit("obstacle", &obstacle, Range::Any(), "obstacle on the demonstrations");
    a->Visit("bias", &bias, Range::Any(), "user bias");
    a->Visit("eval", &eval, Range::Any(), "evaluation");
  }
  void Validate(const std::string& source) const;
};

}  // namespace foresight::imitation
