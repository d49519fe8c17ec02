#pragma once
/// The config of a self-supervised GFCS run (thesis ch 9, "Learning to Sample for Optimisation"
/// and "Self-supervision: Optimisation and Learning in the Loop"): the training and held-out
/// problems, the problem encoding (basis point set + autoencoder), the energy model, the loop and
/// the evaluation. `foresight train configs/gfcs/<name>.yaml`. Torch-free.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "inference/manipulation/bps.h"
#include "inference/manipulation/energy_model.h"
#include "inference/manipulation/fabric.h"
#include "inference/manipulation/gfcs.h"
#include "training/manipulation/config.h"
#include "training/train_config.h"

namespace foresight::gfcs {

/// The autoencoder that reduces the basis-point distances to the context's encoding.
struct AutoencoderConfig {
  int encoding = 300;  ///< thesis: 300
  int hidden = 512;    ///< one hidden layer each side
  double val_fraction = 0.1;
  TrainConfig train = [] {
    TrainConfig t;
    t.epochs = 300;
    t.batch_size = 32;
    t.learning_rate = 1e-3;
    t.patience = 40;
    t.threads = 2;
    return t;
  }();

  template <class A>
  void Serialize(A* a) {
    a->Visit("encoding", &encoding, config::Range::Closed(1, 100000), "encoding size (thesis 300)");
    a->Visit("hidden", &hidden, config::Range::Closed(1, 100000), "hidden layer width");
    a->Visit("val_fraction", &val_fraction, config::Range::Closed(0, 0.9),
             "share of the training scenes held out to stop early");
    a->Visit("train", &train, config::Range::Any(), "trainer settings");
  }
};

/// E_theta(x_c, y): an MLP with `layers` hidden ReLU layers of `hidden` units (thesis 800 x 3).
struct EnergyNetConfig {
  int hidden = 800;
  int layers = 3;

  template <class A>
  void Serialize(A* a) {
    a->Visit("hidden", &hidden, config::Range::Closed(1, 100000), "hidden width (thesis 800)");
    a->Visit("layers", &layers, config::Range::Closed(1, 16), "hidden layers (thesis 3)");
  }
};

/// The self-supervised loop (thesis Algorithm "Self-supervised GFCS").
struct LoopConfig {
  int passes = 2;        ///< passes over the training problems
  int buffer = 200;      ///< positives kept (oldest dropped first)
  int train_every = 25;  ///< n_train: solves between training rounds
  int adam_steps = 800;  ///< per training round
  double learning_rate = 1e-4;
  int batch_positives = 64;  ///< positives per Adam step (each with its negatives)
  int negatives = 16;        ///< N_neg SGLD negatives per positive, drawn before each round
  /// > 0 (not in the thesis): each solve keeps up to this many of its sampler's first-batch
  /// candidates that did not reach the goal (draw order), and each positive is trained against up
  /// to this many of its own problem's kept failures beside its SGLD negatives: the InfoNCE then
  /// also ranks the sampler's labelled mistakes above the solutions of the same problem.
  int failure_negatives = 0;
  manipulation::SgldParams negative_sgld;  ///< SGLD of the negatives (particles, threads: unused)
  bool reached_only = true;                ///< only candidates that reach the goal become positives
  int batches = 30;                        ///< GFCS while training: batches ...
  int batch_size = 30;                     ///< ... of this many candidates (thesis 30 x 30)
  bool shuffle = true;                     ///< solve the training problems in a seeded random order
  int checkpoint_every = 1;                ///< solves between loop checkpoints
  int threads = 2;                         ///< LibTorch intra-op threads
  /// Each Adam step's batch is split into this many fixed shards whose gradients are summed; over
  /// R ranks the shards are dealt round-robin, so training rounds run data-parallel. 1 or 2 shards
  /// give bit-identical models for 1 and 2 ranks (same threads); more shards over more ranks agree
  /// to float rounding only (docs/distributed.md).
  int gradient_shards = 1;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("passes", &passes, Range::Closed(1, 1000), "passes over the training problems");
    a->Visit("buffer", &buffer, Range::Closed(1, 10000000), "positives kept in the buffer");
    a->Visit("train_every", &train_every, Range::Closed(1, 1000000),
             "solves between training rounds (n_train)");
    a->Visit("adam_steps", &adam_steps, Range::Closed(0, 10000000), "Adam steps per round");
    a->Visit("learning_rate", &learning_rate, Range::Positive(), "Adam learning rate");
    a->Visit("batch_positives", &batch_positives, Range::Closed(1, 1000000),
             "positives per Adam step");
    a->Visit("negatives", &negatives, Range::Closed(1, 100000), "SGLD negatives per positive");
    a->Visit("failure_negatives", &failure_negatives, Range::Closed(0, 100000),
             "> 0: per solve, keep up to this many first-batch candidates that failed; per "
             "positive, up to this many of its problem's kept failures as extra InfoNCE negatives "
             "(0: SGLD negatives only, the thesis)");
    a->Visit("negative_sgld", &negative_sgld, Range::Any(),
             "SGLD drawing the negatives (its particles and threads keys are unused: loop.threads "
             "share the buffer entries)");
    a->Visit("reached_only", &reached_only, Range::Any(),
             "only candidates reaching the goal become positives");
    a->Visit("batches", &batches, Range::Closed(1, 1000), "GFCS batches while training");
    a->Visit("batch_size", &batch_size, Range::Closed(2, 100000),
             "GFCS candidates per batch while training");
    a->Visit("shuffle", &shuffle, Range::Any(),
             "solve the training problems in a seeded random order (families interleaved)");
    a->Visit("checkpoint_every", &checkpoint_every, Range::Closed(1, 1000000),
             "solves between loop checkpoints");
    a->Visit("threads", &threads, Range::Closed(1, 256), "LibTorch intra-op threads");
    a->Visit("gradient_shards", &gradient_shards, Range::Closed(1, 1024),
             "fixed shards of each Adam step's batch, dealt over the ranks (data-parallel rounds)");
  }
};

/// Evaluation on held-out problems: GFCS with the uniform and the learned sampler at equal budget,
/// plus baselines (the plan harness's methods).
struct EvalConfig {
  std::vector<manipulation::ProblemsConfig> problems = [] {
    manipulation::ProblemsConfig p;
    p.first = 51;
    p.last = 75;
    return std::vector<manipulation::ProblemsConfig>{p};
  }();
  int batch_size = 20;                ///< candidates per batch at test (thesis 20)
  std::vector<int> batches = {1, 5};  ///< budgets compared (thesis 1 and 5)
  /// > 0: the learned sampler is also evaluated with this share of its batch drawn uniformly
  /// (methods[].uniform_share of the plan harness), in rows beside the thesis's pure one.
  double uniform_share = 0;
  /// The nearest-neighbour sampler (the learned one's trivial baseline: the loop's solutions of
  /// the nearest training problems, nearest_sampler.h) in rows beside the learned sampler.
  bool nearest = true;
  /// > 0: the learned sampler's SGLD step scale at evaluation instead of sampler.step_scale (which
  /// the loop's own solves keep); chosen on validation problems (experiments/gfcs_select.sh SGLD=).
  double step_scale = 0;
  std::vector<manipulation::PlanMethodConfig> baselines = {
      {"GF", manipulation::PlanMethodKind::kFabric, 1, 1.2}};
  double resolution = 0.05;
  double max_joint_speed = 1.0;
  int plot_problems = 2;
  /// Draws per problem (the plan harness's repeats): success rates and the paired differences
  /// (per problem, averaged over its draws) rest on more than one draw of each sampler.
  int repeats = 1;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("problems", &problems, Range::Any(), "held-out problem sets");
    a->Visit("repeats", &repeats, Range::Closed(1, 1000),
             "draws per problem and method (seeds as the plan harness's repeats); paired "
             "differences average each problem's draws");
    a->Visit("batch_size", &batch_size, Range::Closed(2, 100000), "candidates per batch at test");
    a->Visit("batches", &batches, Range::Any(), "GFCS budgets (batches) compared");
    a->Visit("uniform_share", &uniform_share, Range::Closed(0, 1),
             "> 0: also evaluate the learned sampler with this share of its batch drawn uniformly "
             "in the joint limits (rows 'GFCS learned + uniform'); chosen on validation problems");
    a->Visit("nearest", &nearest, Range::Any(),
             "also evaluate the nearest-neighbour sampler (rows 'GFCS nearest': the loop's "
             "solutions of the nearest training problems, the learned sampler's trivial baseline)");
    a->Visit("step_scale", &step_scale, Range::NonNegative(),
             "> 0: the learned sampler's SGLD step scale at evaluation instead of "
             "sampler.step_scale (the loop keeps that); chosen on validation problems");
    a->Visit("baselines", &baselines, Range::Any(), "other methods in the same table");
    a->Visit("resolution", &resolution, Range::Closed(1e-4, 1.0),
             "C-space step of path validity checks (rad)");
    a->Visit("max_joint_speed", &max_joint_speed, Range::Positive(),
             "joint speed used to time planner paths (rad/s)");
    a->Visit("plot_problems", &plot_problems, Range::Closed(0, 100), "problems drawn per family");
  }
};

/// Where the data lives.
struct DataConfig {
  std::string root;  ///< empty: $FORESIGHT_DATA, else ../shared/data

  template <class A>
  void Serialize(A* a) {
    a->Visit("root", &root, config::Range::Any(),
             "data root of the robot and of every problem set without its own root (empty: "
             "$FORESIGHT_DATA, else ../shared/data)");
  }
};

struct ExperimentConfig {
  std::string model = "gfcs";
  std::int64_t seed = 0;
  DataConfig data;
  std::string robot = "franka_panda";  ///< folder under the data root, or "builtin"
  std::vector<manipulation::ProblemsConfig> train_problems = [] {
    manipulation::ProblemsConfig p;
    p.first = 1;
    p.last = 50;
    return std::vector<manipulation::ProblemsConfig>{p};
  }();
  manipulation::FabricParams fabric;
  manipulation::GfcsParams
      gfcs;  ///< commands, top_m, penalty, sigma0, threads (batches: see loop/eval)
  manipulation::BpsLattice lattice;
  AutoencoderConfig autoencoder;
  EnergyNetConfig energy;
  LoopConfig loop;
  manipulation::SgldParams sampler;  ///< the learned sampler at inference (thesis 200 x 50)
  EvalConfig eval;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("model", &model, Range::Any(), "experiment type (gfcs)");
    a->Visit("seed", &seed, Range::Any(), "seed of the networks, the loop and the evaluation");
    a->Visit("data", &data, Range::Any(), "data location");
    a->Visit("robot", &robot, Range::Any(),
             "robot folder under the data root (panda.urdf, spheres_vamp.csv, panda.srdf), or "
             "builtin");
    a->Visit("train_problems", &train_problems, Range::Any(), "problem sets solved by the loop");
    a->Visit("fabric", &fabric, Range::Any(), "geometric fabric");
    a->Visit("gfcs", &gfcs, Range::Any(),
             "GFCS (batches and batch_size: loop.* while training, eval.* at test)");
    a->Visit("lattice", &lattice, Range::Any(), "basis point set lattice (thesis 0.15 m)");
    a->Visit("autoencoder", &autoencoder, Range::Any(), "autoencoder of the BPS distances");
    a->Visit("energy", &energy, Range::Any(), "energy model E(x_c, y)");
    a->Visit("loop", &loop, Range::Any(), "self-supervised loop");
    a->Visit("sampler", &sampler, Range::Any(), "SGLD of the learned sampler at inference");
    a->Visit("eval", &eval, Range::Any(), "held-out evaluation");
  }
  /// Cross-field checks; errors name `path` and the key.
  void Validate(const std::string& path) const;
};

/// The harness config of one held-out problem set (methods: uniform and learned GFCS at each
/// budget, then the baselines), the learned sampler read from `energy_model`.
manipulation::ExperimentConfig EvalPlanConfig(const ExperimentConfig& c,
                                              const manipulation::ProblemsConfig& problems,
                                              const std::string& energy_model);

}  // namespace foresight::gfcs
