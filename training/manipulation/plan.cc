#include "training/manipulation/plan.h"

#include <filesystem>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>

#include "core/bench.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "datasets/data_root.h"
#include "inference/manipulation/builtin_panda.h"
#include "inference/manipulation/energy_model.h"
#include "inference/manipulation/fabric.h"
#include "inference/manipulation/gfcs.h"
#include "inference/manipulation/nearest_sampler.h"
#include "inference/manipulation/planners.h"
#include "inference/manipulation/synthetic_problems.h"
#include "inference/manipulation/validity.h"
#include "training/manipulation/render.h"

namespace foresight::manipulation {
namespace fs = std::filesystem;
using namespace manipulation;  // NOLINT: this file is the manipulation harness

namespace {

/// A method's trajectory before judging: joint states at a fixed step, or nothing.
struct Trajectory {
  bool reached = false;
  std::string status;
  TimedPath joints;
  double generation_time_s = 0;
  RolloutStatusCounts candidates{};   ///< GFCS: how its evaluated candidates ended
  double encode_s = 0, sample_s = 0;  ///< GFCS: of generation_time_s, encoding and first batch
  long long steps = 0;                ///< GFCS: fabric integration steps of the solve
  int stalled = 0;                    ///< GFCS: rollouts ended by the stall test
  int restarts = 0;                   ///< GFCS: batches drawn afresh (gfcs.restart)
};

TimedPath ToTimedPath(const std::vector<JointVector>& states, double dt) {
  TimedPath path;
  path.dt = dt;
  path.positions.resize(kDof, static_cast<Eigen::Index>(states.size()));
  for (std::size_t i = 0; i < states.size(); ++i)
    path.positions.col(static_cast<Eigen::Index>(i)) = states[i];
  return path;
}

/// `sampler`'s world is set by the caller. `best` receives the best candidate (also unsolved).
Trajectory RunGfcs(const Fabric& fabric, const ManipulationProblem& problem,
                   const ExperimentConfig& c, const PlanMethodConfig& method,
                   CommandSampler* sampler, std::uint64_t seed, GfcsCandidate* best) {
  GfcsParams params = c.gfcs;
  params.batches = method.batches;
  params.seed = static_cast<std::int64_t>(seed);
  GfcsQuery query;
  query.start = problem.start;
  query.goal = problem.goal;
  const auto started = bench::Clock::now();
  const GfcsSolution solution = SolveGfcop(fabric, query, sampler, params);
  Trajectory t;
  t.generation_time_s = bench::SecondsSince(started);
  t.sample_s = solution.sample_time_s;
  t.candidates = solution.candidate_statuses;
  t.steps = solution.integration_steps;
  t.stalled = solution.stalled_rollouts;
  t.restarts = solution.restarts;
  if (solution.status == GfcsStatus::kError) {
    t.status = "error: " + solution.message;
    return t;
  }
  if (!solution.top.empty()) *best = solution.top.front();
  if (!solution.solved()) {
    t.status = solution.top.empty() ? "not_solved" : ToString(solution.top.front().last_status);
    return t;
  }
  // Re-roll the best sequence to record its states (deterministic: same as during the solve).
  FabricWorkspace ws = fabric.MakeWorkspace();
  std::vector<JointVector> states;
  *best = EvaluateCommandSequence(fabric, query, solution.top.front().commands, params.penalty, &ws,
                                  &states);
  t.reached = best->reached;
  t.status = t.reached ? "solved" : ToString(best->last_status);
  t.joints = ToTimedPath(states, fabric.params().dt);
  return t;
}

Trajectory RunFabric(const Fabric& fabric, const ManipulationProblem& problem) {
  FabricWorkspace ws = fabric.MakeWorkspace();
  std::vector<JointVector> states{problem.start};
  const auto started = bench::Clock::now();
  const RolloutResult r =
      fabric.Rollout(problem.start, JointVector::Zero(), problem.goal, &ws, &states);
  Trajectory t;
  t.generation_time_s = bench::SecondsSince(started);
  t.reached = r.status == RolloutStatus::kReached;
  t.status = t.reached ? "solved" : ToString(r.status);
  t.joints = ToTimedPath(states, fabric.params().dt);
  return t;
}

Trajectory RunPlanner(PlannerKind kind, const ValidityChecker& checker,
                      const ManipulationProblem& problem, const ExperimentConfig& c,
                      const PlanMethodConfig& method, std::uint64_t seed) {
  KinematicsData data = checker.robot().MakeData();
  auto is_valid = [&](const JointVector& q) { return checker.Check(q, &data) == Validity::kValid; };
  PlannerOptions options;
  options.time_budget_s = method.time_budget;
  options.resolution_rad = c.resolution;
  options.seed = static_cast<std::uint32_t>(seed % 4294967291u) + 1;  // OMPL seeds are >= 1
  const JointLimits& limits = checker.robot().limits();
  const PlannerResult r =
      Plan(kind, problem.start, problem.goal, limits.lower, limits.upper, is_valid, options);
  Trajectory t;
  t.generation_time_s = r.planning_time_s;
  t.reached = r.status == PlannerStatus::kSolved;
  t.status = t.reached ? "solved" : std::string(ToString(r.status));
  if (t.reached)
    t.joints = TimeParameterise(r.waypoints, JointVector::Constant(c.max_joint_speed), c.fabric.dt);
  return t;
}

/// Every consecutive pair of states valid at `resolution`, and the last state at the goal.
std::string JudgePath(const TimedPath& joints, const JointVector& goal,
                      const ValidityChecker& checker, double resolution, double goal_tolerance) {
  KinematicsData data = checker.robot().MakeData();
  const Eigen::Index n = joints.positions.cols();
  if (n == 0) return "empty_path";
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const Validity v = checker.CheckMotion(joints.positions.col(i), joints.positions.col(i + 1),
                                           resolution, &data);
    if (v != Validity::kValid) return std::string("invalid_path: ") + ToString(v);
  }
  if (n == 1 && checker.Check(joints.positions.col(0), &data) != Validity::kValid)
    return "invalid_path";
  if ((joints.positions.col(n - 1) - goal).norm() > goal_tolerance) return "goal_not_reached";
  return "";
}

/// Adds `count` small cylinders centred on end-effector points of the solved trajectory, outside
/// its last second, that do not collide with the start configuration (thesis "reactivity").
bool AddObstaclesOnPath(const Eigen::Matrix3Xd& ee_path, double dt, const ReactivityConfig& r,
                        const ValidityChecker& start_checker, const JointVector& start,
                        std::mt19937_64* rng, World* world) {
  const Eigen::Index usable = ee_path.cols() - static_cast<Eigen::Index>(std::ceil(1.0 / dt));
  if (usable < 2) return false;
  std::uniform_int_distribution<Eigen::Index> pick(1, usable - 1);
  int added = 0;
  for (int attempt = 0; attempt < r.attempts * r.obstacles && added < r.obstacles; ++attempt) {
    Cylinder cyl;
    cyl.X_WC.translation() = ee_path.col(pick(*rng));
    cyl.radius = r.radius;
    cyl.half_height = r.radius;
    World trial = *world;
    trial.AddCylinder("reactive_" + std::to_string(added), cyl);
    const ValidityChecker checker(start_checker.robot(), trial);
    KinematicsData data = checker.robot().MakeData();
    if (checker.Check(start, &data) != Validity::kValid) continue;
    *world = trial;
    ++added;
  }
  return added == r.obstacles;
}

std::string CsvNumber(const std::optional<double>& v) {
  if (!v) return "";
  std::ostringstream os;
  os << std::setprecision(6) << *v;
  return os.str();
}

void WriteProblemsCsv(const std::string& path, const PlanReport& report) {
  std::ostringstream os;
  os << "problem,method,status,success,time_s,ee_length,cspace_length,duration_s,ee_ldj,"
        "cspace_ldj,gfcs_cost,repeat\n";
  for (const PlanAttempt& a : report.attempts) {
    const PathMetrics& m = a.metrics;
    os << a.problem << ",\"" << a.method << "\"," << a.status << "," << (m.success ? 1 : 0) << ","
       << m.time_s << "," << CsvNumber(m.ee_length) << "," << CsvNumber(m.cspace_length) << ","
       << CsvNumber(m.duration_s) << "," << CsvNumber(m.ee_ldj.value) << ","
       << CsvNumber(m.cspace_ldj.value) << "," << CsvNumber(a.gfcs_cost) << "," << a.repeat << "\n";
  }
  WriteFileAtomically(path, os.str());
}

void WriteSummaryJson(const std::string& path, const ExperimentConfig& c,
                      const PlanReport& report) {
  std::ostringstream os;
  os << "{\n  \"family\": \""
     << (c.problems.source == ProblemSource::kSynthetic ? "synthetic" : c.problems.family)
     << "\",\n  \"problems\": " << report.problems << ",\n  \"repeats\": " << c.repeats
     << ",\n  \"invalid_problems\": [";
  for (std::size_t i = 0; i < report.invalid_problems.size(); ++i)
    os << (i ? ", " : "") << report.invalid_problems[i];
  os << "],\n  \"methods\": [\n";
  for (std::size_t i = 0; i < report.methods.size(); ++i) {
    os << "    {\"name\": \"" << report.methods[i].method
       << "\", \"metrics\": " << report.methods[i].summary.ToJson();
    if (c.methods[i].kind == PlanMethodKind::kGfcs) {
      os << ", \"candidate_statuses\": {";
      for (int k = 0; k < kRolloutStatusCount; ++k)
        os << (k ? ", " : "") << "\"" << ToString(static_cast<RolloutStatus>(k))
           << "\": " << report.methods[i].candidate_statuses[k];
      os << "}, \"integration_steps\": " << report.methods[i].work.steps
         << ", \"stalled_rollouts\": " << report.methods[i].work.stalled
         << ", \"restarts\": " << report.methods[i].work.restarts
         << ", \"time_median_s\": {\"total\": " << report.methods[i].median_total_s
         << ", \"encode\": " << report.methods[i].median_encode_s
         << ", \"first_batch_sampling\": " << report.methods[i].median_sample_s << "}";
    }
    os << "}" << (i + 1 < report.methods.size() ? "," : "") << "\n";
  }
  os << "  ]";
  if (c.reactivity.enabled)
    os << ",\n  \"reactivity\": {\"trials\": " << report.reactivity_trials
       << ", \"successes\": " << report.reactivity_successes << ", \"success_rate\": "
       << (report.reactivity_trials
               ? static_cast<double>(report.reactivity_successes) / report.reactivity_trials
               : 0.0)
       << "}";
  os << "\n}\n";
  WriteFileAtomically(path, os.str());
}

}  // namespace

RobotModel LoadExperimentRobot(const ExperimentConfig& c) {
  if (c.robot == "builtin") return BuiltinPanda();
  return RobotModel::LoadPanda(ResolveDataFile(c.problems.root, c.robot));
}

std::vector<ManipulationProblem> LoadExperimentProblems(const ExperimentConfig& c,
                                                        const RobotModel& robot) {
  const ProblemsConfig& p = c.problems;
  if (p.source == ProblemSource::kMotionBenchMaker)
    return LoadMbmFamily(ResolveDataFile(p.root, "motionbenchmaker_panda/problems"), p.family,
                         p.first, p.last);
  std::vector<ManipulationProblem> out;
  const auto is_valid = [&robot](const World& world, const JointVector& q) {
    const ValidityChecker checker(robot, world);
    KinematicsData data = robot.MakeData();
    return checker.Check(q, &data) == Validity::kValid;
  };
  for (int i = 0; i < p.synthetic_count; ++i) {
    out.push_back(MakeSyntheticProblem(p.scene, p.start_goal, robot.limits().lower,
                                       robot.limits().upper, is_valid,
                                       static_cast<std::uint64_t>(p.synthetic_seed + i)));
    out.back().index = i + 1;
  }
  return out;
}

PlanReport RunPlanExperiment(const ExperimentConfig& c, const std::string& run_dir) {
  const RobotModel robot = LoadExperimentRobot(c);
  const std::vector<ManipulationProblem> problems = LoadExperimentProblems(c, robot);
  PlanReport report;
  report.problems = static_cast<int>(problems.size());
  std::vector<std::vector<PathMetrics>> per_method(c.methods.size());
  std::vector<RolloutStatusCounts> candidate_statuses(c.methods.size(), RolloutStatusCounts{});
  std::vector<GfcsWork> work(c.methods.size());
  // GFCS time split per method, one entry per problem.
  struct Times {
    std::vector<double> total, encode, sample;
  };
  std::vector<Times> times(c.methods.size());
  std::vector<PlanProblemPicture> pictures;
  KinematicsData ee_data = robot.MakeData();
  const EndEffectorFn ee = [&](const JointVector& q) {
    ForwardKinematics(robot, q, &ee_data);
    return Eigen::Vector3d(ee_data.p_WE);
  };

  const JointLimits& limits = robot.limits();
  UniformSampler uniform(limits.lower, limits.upper);
  // One learned sampler per method that uses it (each with the method's uniform share).
  std::optional<EnergyModel> energy;
  std::vector<std::optional<LearnedSampler>> learned(c.methods.size());
  std::vector<std::optional<NearestSampler>> nearest(c.methods.size());
  for (std::size_t m = 0; m < c.methods.size(); ++m) {
    const PlanMethodConfig& method = c.methods[m];
    if (method.kind != PlanMethodKind::kGfcs ||
        (method.sampler == GfcsSamplerKind::kUniform && method.nearest_share == 0))
      continue;
    if (!energy) {
      energy.emplace(EnergyModel::Load(c.energy_model));
      log::Info("energy model (learned and nearest samplers): ", c.energy_model);
    }
    if (method.sampler == GfcsSamplerKind::kNearest || method.nearest_share > 0 ||
        method.sgld_init == SgldInit::kMemory) {
      try {
        nearest[m].emplace(
            *energy, method.nearest_per_problem > 0 ? method.nearest_per_problem : c.gfcs.top_m);
      } catch (const Error& e) {
        Fail(c.energy_model, ": method '", method.name, "': ", e.what());
      }
    }
    if (method.sampler != GfcsSamplerKind::kLearned) continue;
    SgldParams sgld = c.sgld;
    sgld.uniform_share = method.uniform_share;
    sgld.pick = method.sgld_pick;
    learned[m].emplace(*energy, sgld);
    if (method.sgld_init == SgldInit::kMemory) learned[m]->SetStart(&*nearest[m]);
  }

  // Reactivity is measured on the first GFCS method's solutions.
  int reactive_method = -1;
  for (std::size_t m = 0; m < c.methods.size() && reactive_method < 0; ++m)
    if (c.methods[m].kind == PlanMethodKind::kGfcs) reactive_method = static_cast<int>(m);

  for (const ManipulationProblem& problem : problems) {
    const ValidityChecker checker(robot, problem.world);
    KinematicsData data = robot.MakeData();
    const Validity start_ok = checker.Check(problem.start, &data);
    const Validity goal_ok = checker.Check(problem.goal, &data);
    if (start_ok != Validity::kValid || goal_ok != Validity::kValid) {
      log::Info("problem ", problem.index, ": start ", ToString(start_ok), ", goal ",
                ToString(goal_ok), " for this robot model: skipped");
      report.invalid_problems.push_back(problem.index);
      continue;
    }
    const Fabric fabric(robot, problem.world, c.fabric);
    PlanProblemPicture picture;
    picture.problem = problem.index;
    picture.world = &problem.world;
    std::ostringstream line;
    line << "problem " << problem.index << ":";
    for (int repeat = 0; repeat < c.repeats; ++repeat) {
      const std::uint64_t seed =
          static_cast<std::uint64_t>(c.seed + problem.index + repeat * kRepeatSeedStride);
      if (c.repeats > 1) line << (repeat ? " |" : "") << " draw " << repeat << ":";
      for (std::size_t m = 0; m < c.methods.size(); ++m) {
        const PlanMethodConfig& method = c.methods[m];
        Trajectory t;
        GfcsCandidate best;
        std::optional<double> attempt_cost;
        try {
          switch (method.kind) {
            case PlanMethodKind::kGfcs: {
              CommandSampler* sampler = &uniform;
              double encode_s = 0;  // the world's encoding is part of the learned method's time
              const auto started = bench::Clock::now();
              // One encoding of the world per method, shared by its two samplers.
              if (nearest[m]) nearest[m]->SetWorld(problem.world);
              if (learned[m]) {
                if (nearest[m])
                  learned[m]->SetEncoding(nearest[m]->encoding());
                else
                  learned[m]->SetWorld(problem.world);
                sampler = &*learned[m];
              }
              std::optional<SplitSampler> split;
              if (nearest[m]) {
                if (method.sampler == GfcsSamplerKind::kNearest) {
                  sampler = &*nearest[m];
                } else if (method.nearest_share > 0) {  // that share from the memory, the rest
                                                        // from `sampler`
                  split.emplace(&*nearest[m], method.nearest_share, sampler);
                  sampler = &*split;
                }
              }
              if (learned[m] || nearest[m]) encode_s = bench::SecondsSince(started);
              t = RunGfcs(fabric, problem, c, method, sampler, seed, &best);
              t.generation_time_s += encode_s;
              t.encode_s = encode_s;
              attempt_cost = best.commands.size() ? best.cost : std::optional<double>();
              break;
            }
            case PlanMethodKind::kFabric:
              t = RunFabric(fabric, problem);
              break;
            case PlanMethodKind::kBiEst:
              t = RunPlanner(PlannerKind::kBiEst, checker, problem, c, method, seed);
              break;
            case PlanMethodKind::kBitStar:
              t = RunPlanner(PlannerKind::kBitStar, checker, problem, c, method, seed);
              break;
            case PlanMethodKind::kRrtConnect:
              t = RunPlanner(PlannerKind::kRrtConnect, checker, problem, c, method, seed);
              break;
          }
        } catch (const std::exception& e) {
          t = Trajectory{};
          t.status = std::string("error: ") + e.what();
        }
        PlanAttempt attempt;
        attempt.method = method.name;
        attempt.problem = problem.index;
        attempt.repeat = repeat;
        attempt.status = t.status;
        attempt.gfcs_cost = attempt_cost;
        if (t.reached) {
          const std::string verdict = JudgePath(t.joints, problem.goal, checker, c.resolution,
                                                c.fabric.goal_tolerance + 1e-9);
          if (!verdict.empty()) {
            t.reached = false;
            attempt.status = verdict;
          }
        }
        if (t.reached) {
          attempt.ee_path = EndEffectorPath(t.joints, ee);
          attempt.metrics = EvaluatePath(t.joints, attempt.ee_path, t.generation_time_s);
          attempt.metrics.success = true;
        } else {
          attempt.metrics = PathMetrics::Failure(t.generation_time_s);
        }
        line << " " << method.name << "=" << attempt.status;
        per_method[m].push_back(attempt.metrics);
        for (int k = 0; k < kRolloutStatusCount; ++k) candidate_statuses[m][k] += t.candidates[k];
        work[m].steps += t.steps;
        work[m].stalled += t.stalled;
        work[m].restarts += t.restarts;
        if (method.kind == PlanMethodKind::kGfcs) {
          times[m].total.push_back(t.generation_time_s);
          times[m].encode.push_back(t.encode_s);
          times[m].sample.push_back(t.sample_s);
        }

        // Reactivity: GFCS's commands re-run by the fabric with obstacles on the solved path.
        if (c.reactivity.enabled && repeat == 0 && static_cast<int>(m) == reactive_method &&
            attempt.metrics.success) {
          World changed = problem.world;
          std::mt19937_64 rng(seed);
          if (AddObstaclesOnPath(attempt.ee_path, c.fabric.dt, c.reactivity, checker, problem.start,
                                 &rng, &changed)) {
            const Fabric reactive(robot, changed, c.fabric);
            FabricWorkspace ws = reactive.MakeWorkspace();
            GfcsQuery query;
            query.start = problem.start;
            query.goal = problem.goal;
            const GfcsCandidate again =
                EvaluateCommandSequence(reactive, query, best.commands, c.gfcs.penalty, &ws);
            ++report.reactivity_trials;
            report.reactivity_successes += again.reached;
          }
        }
        if (repeat == 0 && static_cast<int>(pictures.size()) < c.plot_problems)
          picture.paths.push_back({method.name, attempt.ee_path});
        report.attempts.push_back(std::move(attempt));
      }
    }
    log::Info(line.str());
    if (static_cast<int>(pictures.size()) < c.plot_problems) pictures.push_back(picture);
  }
  for (std::size_t m = 0; m < c.methods.size(); ++m) {
    PlanMethodResult result;
    result.method = c.methods[m].name;
    result.summary = Summarise(per_method[m]);
    result.candidate_statuses = candidate_statuses[m];
    result.work = work[m];
    if (!times[m].total.empty()) {
      result.median_total_s = bench::Median(times[m].total);
      result.median_encode_s = bench::Median(times[m].encode);
      result.median_sample_s = bench::Median(times[m].sample);
    }
    report.methods.push_back(std::move(result));
  }

  WriteSummaryJson((fs::path(run_dir) / "summary.json").string(), c, report);
  WriteProblemsCsv((fs::path(run_dir) / "problems.csv").string(), report);
  if (!pictures.empty()) {
    // Pictures keep pointers to the problems' worlds, alive until here.
    RenderEndEffectorPaths((fs::path(run_dir) / "ee_paths.png").string(), pictures);
  }
  return report;
}

}  // namespace foresight::manipulation
