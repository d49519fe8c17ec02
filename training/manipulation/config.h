#pragma once
/// The config of a manipulation experiment (thesis ch 9): which problems, which methods, the
/// fabric, GFCS and planner parameters. Run by `foresight plan CONFIG`
/// (training/manipulation/plan.h). Torch-free.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "inference/manipulation/energy_model.h"
#include "inference/manipulation/fabric.h"
#include "inference/manipulation/gfcs.h"
#include "inference/manipulation/synthetic_problems.h"

namespace foresight::manipulation {

/// Where the problems come from.
enum class ProblemSource { kMotionBenchMaker, kSynthetic };

struct ProblemsConfig {
  ProblemSource source = ProblemSource::kMotionBenchMaker;
  /// Data root (empty: $FORESIGHT_DATA, else ../shared/data; datasets/data_root.h).
  std::string root;
  std::string family = "table_under_pick_panda";  ///< MotionBenchMaker family (mbm)
  int first = 51, last = 75;  ///< problem numbers, inclusive (thesis: 1-50 develop, 51-75 report)
  std::int64_t synthetic_seed = 0;           ///< synthetic scenes: seed of problem i is seed + i
  int synthetic_count = 4;                   ///< synthetic scenes generated
  manipulation::SyntheticSceneConfig scene;  ///< synthetic scenes
  manipulation::StartGoalConfig start_goal;  ///< synthetic start and goal draws

  template <class A>
  void Serialize(A* a) {
    a->VisitEnum("source", &source,
                 config::EnumNames<ProblemSource>{{ProblemSource::kMotionBenchMaker, "mbm"},
                                                  {ProblemSource::kSynthetic, "synthetic"}},
                 "mbm: MotionBenchMaker problems under root; synthetic: generated scenes");
    a->Visit("root", &root, config::Range::Any(),
             "data root (empty: $FORESIGHT_DATA, else ../shared/data)");
    a->Visit("family", &family, config::Range::Any(), "MotionBenchMaker family, e.g. box_panda");
    a->Visit("first", &first, config::Range::Closed(1, 100000), "first problem number");
    a->Visit("last", &last, config::Range::Closed(1, 100000), "last problem number (inclusive)");
    a->Visit("synthetic_seed", &synthetic_seed, config::Range::Any(), "seed of synthetic scenes");
    a->Visit("synthetic_count", &synthetic_count, config::Range::Closed(1, 100000),
             "synthetic scenes generated");
    a->Visit("scene", &scene, config::Range::Any(), "synthetic scenes: what they hold");
    a->Visit("start_goal", &start_goal, config::Range::Any(), "synthetic start and goal draws");
  }
};

/// What kind of method a row of the comparison is.
enum class PlanMethodKind { kGfcs, kFabric, kBiEst, kBitStar, kRrtConnect };

/// Where GFCS's first batch comes from.
enum class GfcsSamplerKind { kUniform, kLearned, kNearest };
/// Where the learned sampler's SGLD particles start.
enum class SgldInit { kUniform, kMemory };

/// One row of the comparison table.
struct PlanMethodConfig {
  std::string name = "GFCS (1 batch)";  ///< label in summary.json and the table
  PlanMethodKind kind = PlanMethodKind::kGfcs;
  int batches = 1;                                      ///< gfcs: batches evaluated
  double time_budget = 1.2;                             ///< planners: seconds
  GfcsSamplerKind sampler = GfcsSamplerKind::kUniform;  ///< gfcs: first batch
  /// gfcs with the learned sampler: share of the first batch drawn uniformly in the joint limits
  /// (SgldParams::uniform_share; 0 = the thesis).
  double uniform_share = 0;
  /// gfcs with the learned sampler: which SGLD survivors fill the batch (SgldParams::pick).
  SgldPick sgld_pick = SgldPick::kLowestEnergy;
  /// gfcs with sampler uniform or learned: share of the first batch taken from energy_model's
  /// solution memory as the nearest sampler takes it (SplitSampler), the rest from `sampler`.
  double nearest_share = 0;
  /// gfcs with the nearest sampler (or a nearest_share): solutions taken from each memory problem
  /// (0: gfcs.top_m, the number a loop's solve keeps).
  int nearest_per_problem = 0;
  /// gfcs with the learned sampler: SGLD's particles start uniform (the thesis) or at the nearest
  /// sampler's candidates from energy_model's solution memory (LearnedSampler::SetStart).
  SgldInit sgld_init = SgldInit::kUniform;

  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &name, config::Range::Any(), "label of the method in the outputs");
    a->VisitEnum("kind", &kind,
                 config::EnumNames<PlanMethodKind>{{PlanMethodKind::kGfcs, "gfcs"},
                                                   {PlanMethodKind::kFabric, "gf"},
                                                   {PlanMethodKind::kBiEst, "biest"},
                                                   {PlanMethodKind::kBitStar, "bitstar"},
                                                   {PlanMethodKind::kRrtConnect, "rrtconnect"}},
                 "gfcs, gf (one attractor to the goal), biest, bitstar or rrtconnect");
    a->Visit("batches", &batches, config::Range::Closed(1, 1000), "gfcs: batches evaluated");
    a->Visit("time_budget", &time_budget, config::Range::OpenClosed(0, 3600),
             "planners: time budget (s)");
    a->VisitEnum("sampler", &sampler,
                 config::EnumNames<GfcsSamplerKind>{{GfcsSamplerKind::kUniform, "uniform"},
                                                    {GfcsSamplerKind::kLearned, "learned"},
                                                    {GfcsSamplerKind::kNearest, "nearest"}},
                 "gfcs: first batch uniform in the joint limits, SGLD on energy_model (learned), "
                 "or the solutions of the nearest training problems in energy_model's memory "
                 "(nearest: the trivial baseline of learned)");
    a->Visit("uniform_share", &uniform_share, config::Range::Closed(0, 1),
             "gfcs, sampler learned: share of the first batch drawn uniformly in the joint limits "
             "beside the SGLD samples (0: the thesis)");
    a->VisitEnum("sgld_pick", &sgld_pick,
                 config::EnumNames<SgldPick>{{SgldPick::kLowestEnergy, "lowest"},
                                             {SgldPick::kRandom, "random"}},
                 "gfcs, sampler learned: the lowest-energy SGLD survivors, or a random draw of "
                 "them (the spread of the SGLD distribution)");
    a->Visit("nearest_share", &nearest_share, config::Range::Closed(0, 1),
             "gfcs, sampler uniform or learned: share of the first batch taken from "
             "energy_model's solution memory as sampler: nearest takes it, the rest from sampler");
    a->Visit("nearest_per_problem", &nearest_per_problem, config::Range::Closed(0, 10000),
             "gfcs, nearest sampler or nearest_share: solutions taken from each nearest memory "
             "problem (0: gfcs.top_m)");
    a->VisitEnum(
        "sgld_init", &sgld_init,
        config::EnumNames<SgldInit>{{SgldInit::kUniform, "uniform"}, {SgldInit::kMemory, "memory"}},
        "gfcs, sampler learned: SGLD particles start uniform in the joint limits (the "
        "thesis) or at the nearest sampler's candidates from energy_model's memory");
  }
};

/// Obstacles added on the solved path after solving (thesis "reactivity").
struct ReactivityConfig {
  bool enabled = false;
  int obstacles = 1;     ///< added per problem
  double radius = 0.05;  ///< m, cylinders' radius (and half height)
  int attempts = 50;     ///< samples tried per obstacle before giving up on the problem

  template <class A>
  void Serialize(A* a) {
    a->Visit("enabled", &enabled, config::Range::Any(),
             "re-run GFCS's commands with new obstacles");
    a->Visit("obstacles", &obstacles, config::Range::Closed(1, 20), "obstacles added per problem");
    a->Visit("radius", &radius, config::Range::Closed(0.005, 0.5), "obstacle radius (m)");
    a->Visit("attempts", &attempts, config::Range::Closed(1, 100000),
             "placements tried per obstacle");
  }
};

/// The thesis's comparison (Table "Evaluated metrics"): GF, Bi-EST, BIT* (1.2 s, 6 s), GFCS (1
/// and 5 batches), plus RRT-Connect (VAMP's published reference on these problems).
std::vector<PlanMethodConfig> DefaultPlanMethods();

/// Seed offset between the draws of one problem (ExperimentConfig::repeats); a prime, far beyond
/// any problem index.
inline constexpr std::int64_t kRepeatSeedStride = 1000003;

struct ExperimentConfig {
  std::string model = "manipulation";
  std::int64_t seed = 0;
  /// Robot folder with panda.urdf, spheres_vamp.csv, panda.srdf, relative to the data root;
  /// "builtin": the built-in Panda (no data needed).
  std::string robot = "franka_panda";
  ProblemsConfig problems;
  std::vector<PlanMethodConfig> methods = DefaultPlanMethods();
  manipulation::FabricParams fabric;
  manipulation::GfcsParams gfcs;
  double resolution = 0.05;      ///< rad, C-space step of the path validity checks (every method)
  double max_joint_speed = 1.0;  ///< rad/s, timing of planner paths (metrics)
  ReactivityConfig reactivity;
  int plot_problems = 3;  ///< problems drawn in ee_paths.png
  /// Draws per problem: every method runs `repeats` times on each problem, draw r with the seed
  /// seed + i + r kRepeatSeedStride (draw 0 is the single run's), so success rates of randomised
  /// methods are estimated from more than one draw. Reactivity and pictures use draw 0.
  int repeats = 1;
  std::string energy_model;       ///< artifact of the learned sampler (a gfcs run's model.h5)
  manipulation::SgldParams sgld;  ///< the learned sampler's SGLD

  template <class A>
  void Serialize(A* a) {
    a->Visit("model", &model, config::Range::Any(), "experiment type (manipulation)");
    a->Visit("seed", &seed, config::Range::Any(), "seed of the methods (problem i uses seed + i)");
    a->Visit("robot", &robot, config::Range::Any(),
             "robot folder under the data root (panda.urdf, spheres_vamp.csv, panda.srdf), or "
             "builtin");
    a->Visit("problems", &problems, config::Range::Any(), "motion problems");
    a->Visit("methods", &methods, config::Range::Any(), "methods compared");
    a->Visit("fabric", &fabric, config::Range::Any(), "geometric fabric");
    a->Visit("gfcs", &gfcs, config::Range::Any(), "geometric fabric command sequences");
    a->Visit("resolution", &resolution, config::Range::Closed(1e-4, 1.0),
             "C-space step of path validity checks (rad)");
    a->Visit("max_joint_speed", &max_joint_speed, config::Range::Positive(),
             "joint speed used to time planner paths (rad/s)");
    a->Visit("reactivity", &reactivity, config::Range::Any(), "obstacles added on solved paths");
    a->Visit("plot_problems", &plot_problems, config::Range::Closed(0, 100),
             "problems drawn in ee_paths.png");
    a->Visit("repeats", &repeats, config::Range::Closed(1, 1000),
             "draws per problem and method (draw r seeded seed + i + r * 1000003; 0: the single "
             "run's)");
    a->Visit("energy_model", &energy_model, config::Range::Any(),
             "artifact of the learned sampler (a gfcs run's model.h5; methods with sampler: "
             "learned or nearest)");
    a->Visit("sgld", &sgld, config::Range::Any(), "SGLD of the learned sampler");
  }
  /// Cross-field checks; errors name `path` and the key.
  void Validate(const std::string& path) const;
};

}  // namespace foresight::manipulation
