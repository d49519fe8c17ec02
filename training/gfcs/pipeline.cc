#include "training/gfcs/pipeline.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <random>
#include <sstream>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "inference/manipulation/bps.h"
#include "inference/manipulation/energy_model.h"
#include "inference/manipulation/validity.h"
#include "models/gfcs/gfcs_nets.h"
#include "training/distributed.h"
#include "training/gfcs/loop.h"
#include "training/manipulation/plan.h"
#include "training/run_dir.h"
#include "training/trainer.h"

namespace foresight::gfcs {
namespace fs = std::filesystem;
using namespace manipulation;  // NOLINT: this file is the gfcs pipeline

namespace {

/// A gfcs run directory holds these; a fresh start refuses a directory holding one.
const RunDirectoryRules kGfcsRunRules{{"checkpoints", "autoencoder", "model.h5"}, true};

/// The harness config that loads the robot and one problem set.
manipulation::ExperimentConfig HarnessConfig(const ExperimentConfig& c,
                                             const manipulation::ProblemsConfig& set) {
  manipulation::ExperimentConfig mc;
  mc.seed = c.seed;
  mc.robot = c.robot;
  mc.problems = set;
  if (mc.problems.root.empty()) mc.problems.root = c.data.root;
  mc.fabric = c.fabric;
  mc.gfcs = c.gfcs;
  return mc;
}

std::string SetName(const manipulation::ProblemsConfig& set) {
  return set.source == manipulation::ProblemSource::kSynthetic ? "synthetic" : set.family;
}

/// The training problems whose start and goal are valid for the robot model (others skipped).
std::vector<TrainingProblem> LoadTrainingProblems(const ExperimentConfig& c,
                                                  const RobotModel& robot) {
  std::vector<TrainingProblem> out;
  for (const manipulation::ProblemsConfig& set : c.train_problems) {
    int skipped = 0;
    for (ManipulationProblem& p :
         manipulation::LoadExperimentProblems(HarnessConfig(c, set), robot)) {
      const ValidityChecker checker(robot, p.world);
      KinematicsData data = robot.MakeData();
      if (checker.Check(p.start, &data) != Validity::kValid ||
          checker.Check(p.goal, &data) != Validity::kValid) {
        ++skipped;
        continue;
      }
      out.push_back({SetName(set), std::move(p), {}});
    }
    if (skipped)
      log::Info(SetName(set), ": ", skipped, " problems with an invalid start or goal skipped");
  }
  return out;
}

/// The autoencoder's training task: reconstruction error of normalised BPS distances.
class AutoencoderTask : public TrainingTask {
 public:
  AutoencoderTask(BpsAutoencoder ae, torch::Tensor train, torch::Tensor val)
      : ae_(std::move(ae)), train_(std::move(train)), val_(std::move(val)) {}
  torch::nn::Module& module() override { return *ae_; }
  std::int64_t num_train() const override { return train_.size(0); }
  torch::Tensor BatchLoss(const torch::Tensor& indices) override {
    const torch::Tensor x = train_.index_select(0, indices);
    return torch::mse_loss(ae_->forward(x), x);
  }
  double ValidationLoss() override {
    torch::NoGradGuard no_grad;
    const torch::Tensor& x = val_.size(0) > 0 ? val_ : train_;
    return torch::mse_loss(ae_->forward(x), x).item<double>();
  }

 private:
  BpsAutoencoder ae_;
  torch::Tensor train_, val_;
};

torch::Tensor RowsToTensor(const std::vector<Eigen::VectorXf>& rows) {
  torch::Tensor t =
      torch::empty({static_cast<std::int64_t>(rows.size()), rows.front().size()}, torch::kFloat32);
  for (std::size_t i = 0; i < rows.size(); ++i)
    std::copy(rows[i].data(), rows[i].data() + rows[i].size(),
              t[static_cast<std::int64_t>(i)].data_ptr<float>());
  return t;
}

/// BPS distances of the training worlds, their normalisation, and the autoencoder (trained by the
/// trainer in run_dir/autoencoder, resumable). `*interrupted` when the trainer was stopped.
Encoding TrainEncoding(const ExperimentConfig& c, const RobotModel& robot,
                       const std::vector<TrainingProblem>& problems, const std::string& run_dir,
                       bool resume, const std::atomic<bool>* interrupt, bool* interrupted) {
  CheckLatticeCovers(c.lattice, ReachBox(robot), "lattice");
  std::vector<Eigen::VectorXf> bps;
  for (const TrainingProblem& p : problems) bps.push_back(EncodeBps(p.problem.world, c.lattice));
  const Eigen::Index n_r = bps.front().size();
  Encoding enc;
  enc.bps_mean = Eigen::VectorXf::Zero(n_r);
  for (const auto& b : bps) enc.bps_mean += b;
  enc.bps_mean /= static_cast<float>(bps.size());
  Eigen::VectorXf var = Eigen::VectorXf::Zero(n_r);
  for (const auto& b : bps) var += (b - enc.bps_mean).cwiseAbs2();
  // Reference points no scene comes near are constant: a floor keeps them at ~0, not inf.
  enc.bps_std = (var / static_cast<float>(bps.size())).cwiseSqrt().cwiseMax(0.01f);
  for (auto& b : bps) b = (b - enc.bps_mean).cwiseQuotient(enc.bps_std);
  log::Info("basis point set: ", n_r, " reference points (", c.lattice.spacing, " m lattice), ",
            bps.size(), " training scenes");

  // Held-out scenes for early stopping, a seeded choice.
  std::vector<std::size_t> order(bps.size());
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(static_cast<std::uint64_t>(c.seed) + 7);
  std::shuffle(order.begin(), order.end(), rng);
  const std::size_t n_val =
      bps.size() > 1 ? static_cast<std::size_t>(std::floor(c.autoencoder.val_fraction * bps.size()))
                     : 0;
  std::vector<Eigen::VectorXf> train, val;
  for (std::size_t i = 0; i < order.size(); ++i) (i < n_val ? val : train).push_back(bps[order[i]]);

  torch::manual_seed(static_cast<std::uint64_t>(c.seed));
  BpsAutoencoder ae(static_cast<int>(n_r), c.autoencoder.hidden, c.autoencoder.encoding);
  AutoencoderTask task(ae, RowsToTensor(train),
                       val.empty() ? torch::empty({0, n_r}) : RowsToTensor(val));
  // Every rank trains the (small) autoencoder itself, in its own folder, not data-parallel: the
  // encoder, hence every context, is then bit-identical for any number of ranks.
  const int rank = dist::DefaultGroup()->rank();
  const RunPaths run{run_dir + "/autoencoder" + (rank ? ".rank" + std::to_string(rank) : "")};
  fs::create_directories(run.dir);
  TrainHooks hooks;
  hooks.interrupt = interrupt;
  const auto local = dist::Group::Local();
  const TrainingSummary s =
      Train(&task, c.autoencoder.train, run, static_cast<std::uint64_t>(c.seed),
            resume && fs::exists(run.Checkpoint()), hooks, local.get());
  *interrupted = s.reason == TerminationReason::kInterrupted;
  if (*interrupted) return enc;
  const std::string ckpt =
      fs::exists(run.BestCheckpoint()) ? run.BestCheckpoint() : run.Checkpoint();
  FS_THROW_UNLESS(fs::exists(ckpt), run.dir, ": the autoencoder left no checkpoint (",
                  ToString(s.reason), ")");
  LoadCheckpointModel(ckpt, ae.ptr().get());
  log::Info("autoencoder: ", s.BriefReport());
  enc.encoder = ae->encoder()->ToMlp();
  return enc;
}

/// Fills the problems' contexts [q0, qd0, qg, encoding] with the engine's own encoder.
void EncodeProblems(const ExperimentConfig& c, const RobotModel& robot, const Encoding& enc,
                    std::vector<TrainingProblem>* problems) {
  const int context = 3 * kDof + enc.encoder.output_size();
  const int command = kDof * (c.gfcs.commands - 1);
  // Energy weights do not enter the context: a placeholder layer of the right width.
  DenseLayer placeholder;
  placeholder.weight = Eigen::MatrixXf::Zero(1, context + command);
  placeholder.bias = Eigen::VectorXf::Zero(1);
  const EnergyModel model(MakeEnergyParts(c, robot, enc, Mlp({placeholder})));
  for (TrainingProblem& p : *problems) {
    GfcsQuery q;
    q.start = p.problem.start;
    q.goal = p.problem.goal;
    model.Context(q, model.EncodeWorld(p.problem.world), &p.context);
  }
}

void WriteArtifact(const ExperimentConfig& c, const RobotModel& robot, const Encoding& enc,
                   const Mlp& energy, manipulation::SolutionMemory memory, const std::string& yaml,
                   const std::string& path) {
  manipulation::EnergyModelParts parts = MakeEnergyParts(c, robot, enc, energy);
  parts.memory = std::move(memory);
  EnergyModel(std::move(parts)).Save(path, yaml, c.seed);
  (void)EnergyModel::Load(path);  // the engine loads what was written
}

RobotModel LoadRobot(const ExperimentConfig& c) {
  FS_THROW_UNLESS(!c.train_problems.empty(), "gfcs: train_problems is empty");
  return manipulation::LoadExperimentRobot(HarnessConfig(c, c.train_problems.front()));
}

// --- Evaluation -------------------------------------------------------------------------------

struct PairedDifference {
  int n = 0;
  double mean = NAN, lo = NAN, hi = NAN;  ///< NaN (JSON null) without pairs
};

/// Mean of `d` with a 95 % percentile-bootstrap interval (2000 resamples, fixed seed).
PairedDifference Bootstrap(const std::vector<double>& d, std::uint64_t seed) {
  PairedDifference out;
  out.n = static_cast<int>(d.size());
  if (d.empty()) return out;
  out.mean = 0;
  for (double v : d) out.mean += v / static_cast<double>(d.size());
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, d.size() - 1);
  std::vector<double> means(2000);
  for (double& m : means) {
    double s = 0;
    for (std::size_t i = 0; i < d.size(); ++i) s += d[pick(rng)];
    m = s / static_cast<double>(d.size());
  }
  std::sort(means.begin(), means.end());
  out.lo = means[50];
  out.hi = means[1949];
  return out;
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    if (static_cast<unsigned char>(ch) < 0x20) continue;
    out += ch;
  }
  return out + "\"";
}

std::string Num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os << std::setprecision(6) << v;
  return os.str();
}

std::string BudgetLabel(int batches) {
  return std::to_string(batches) + (batches == 1 ? " batch" : " batches");
}

/// "GFCS learned + 25 % uniform": the defensive mixture's rows.
std::string MixedLabel(double uniform_share) {
  std::ostringstream os;
  os << "GFCS learned + " << std::setprecision(3) << 100 * uniform_share << " % uniform";
  return os.str();
}

}  // namespace

manipulation::ExperimentConfig EvalPlanConfig(const ExperimentConfig& c,
                                              const manipulation::ProblemsConfig& problems,
                                              const std::string& energy_model) {
  manipulation::ExperimentConfig mc = HarnessConfig(c, problems);
  mc.gfcs.batch_size = c.eval.batch_size;
  mc.methods.clear();
  for (int b : c.eval.batches) {
    mc.methods.push_back({"GFCS uniform (" + BudgetLabel(b) + ")",
                          manipulation::PlanMethodKind::kGfcs, b, 1.2,
                          manipulation::GfcsSamplerKind::kUniform});
    mc.methods.push_back({"GFCS learned (" + BudgetLabel(b) + ")",
                          manipulation::PlanMethodKind::kGfcs, b, 1.2,
                          manipulation::GfcsSamplerKind::kLearned});
    if (c.eval.uniform_share > 0)
      mc.methods.push_back({MixedLabel(c.eval.uniform_share) + " (" + BudgetLabel(b) + ")",
                            manipulation::PlanMethodKind::kGfcs, b, 1.2,
                            manipulation::GfcsSamplerKind::kLearned, c.eval.uniform_share});
    if (c.eval.nearest)
      mc.methods.push_back({"GFCS nearest (" + BudgetLabel(b) + ")",
                            manipulation::PlanMethodKind::kGfcs, b, 1.2,
                            manipulation::GfcsSamplerKind::kNearest});
  }
  for (const manipulation::PlanMethodConfig& m : c.eval.baselines) mc.methods.push_back(m);
  mc.resolution = c.eval.resolution;
  mc.max_joint_speed = c.eval.max_joint_speed;
  mc.plot_problems = c.eval.plot_problems;
  mc.repeats = c.eval.repeats;
  mc.energy_model = energy_model;
  mc.sgld = c.sampler;
  if (c.eval.step_scale > 0) mc.sgld.step_scale = c.eval.step_scale;  // chosen on validation
  return mc;
}

bool TrainRun(const ExperimentConfig& c, const std::string& run_dir, bool resume,
              const std::atomic<bool>* interrupt, bool check_eval_sets) {
  const std::string yaml = config::ToYaml(c);
  const auto group = dist::DefaultGroup();
  if (group->rank() == 0) {
    StartRunDirectory(run_dir, yaml, resume, kGfcsRunRules);
  } else {  // rank 0 owns config.yaml and log.txt (the directory may be shared)
    fs::create_directories(run_dir);
    log::SetFile(run_dir + "/log.rank" + std::to_string(group->rank()) + ".txt");
  }
  group->Barrier();  // rank 0's checks passed (or it failed, and the barrier fails for all)
  log::Info(resume ? "resuming" : "starting", " self-supervised GFCS in ", run_dir, " (seed ",
            c.seed, ", rank ", group->rank(), " of ", group->size(), ")");
  const RobotModel robot = LoadRobot(c);
  // The held-out sets are read now, so a missing file fails before an hour of training, not after.
  if (check_eval_sets)
    for (const manipulation::ProblemsConfig& set : c.eval.problems)
      (void)manipulation::LoadExperimentProblems(HarnessConfig(c, set), robot);
  std::vector<TrainingProblem> problems = LoadTrainingProblems(c, robot);
  FS_THROW_UNLESS(!problems.empty(), run_dir, ": no training problem has a valid start and goal");
  if (c.loop.shuffle) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(c.seed) + 11);
    std::shuffle(problems.begin(), problems.end(), rng);
  }
  bool interrupted = false;
  const Encoding enc = TrainEncoding(c, robot, problems, run_dir, resume, interrupt, &interrupted);
  if (interrupted) return false;
  EncodeProblems(c, robot, enc, &problems);
  Mlp energy;
  manipulation::SolutionMemory memory;
  const LoopStats stats = RunSelfSupervisedLoop(c, yaml, robot, enc, problems, run_dir, resume,
                                                interrupt, &energy, &memory);
  if (group->rank() == 0)
    WriteFileAtomically(run_dir + "/loop_summary.json", stats.ToJson() + "\n");
  if (stats.interrupted) return false;
  log::Info("loop: ", stats.solved, "/", stats.solves, " solved, ", stats.rounds,
            " training rounds; solving ", stats.solve_seconds, " s, negatives ",
            stats.negative_seconds, " s, training ", stats.train_seconds, " s, the whole loop ",
            stats.loop_seconds, " s (this invocation)");
  if (group->rank() == 0)
    WriteArtifact(c, robot, enc, energy, std::move(memory), yaml, run_dir + "/" + kGfcsArtifact);
  return true;
}

std::string ExportRun(const std::string& run_dir) {
  const auto c = config::LoadExperimentConfig<ExperimentConfig>(run_dir + "/config.yaml");
  const std::string yaml = config::ToYaml(c);
  Encoding enc;
  Mlp energy;
  manipulation::SolutionMemory memory;
  LoadLoopResult(c, yaml, run_dir, &enc, &energy, &memory);
  const std::string path = run_dir + "/" + kGfcsArtifact;
  WriteArtifact(c, LoadRobot(c), enc, energy, std::move(memory), yaml, path);
  return path;
}

PairedPerProblem PairPerProblem(const std::vector<manipulation::PlanAttempt>& attempts,
                                const std::string& uniform, const std::string& learned) {
  using Pair = std::pair<const manipulation::PlanAttempt*, const manipulation::PlanAttempt*>;
  std::map<int, std::map<int, Pair>> by_problem;  // problem -> draw -> (uniform, learned)
  for (const manipulation::PlanAttempt& a : attempts) {
    if (a.method == uniform) by_problem[a.problem][a.repeat].first = &a;
    if (a.method == learned) by_problem[a.problem][a.repeat].second = &a;
  }
  const auto errored = [](const manipulation::PlanAttempt& a) {
    return a.status.rfind("error", 0) == 0;
  };
  struct Mean {
    double sum = 0;
    int n = 0;
    void Add(double v) { sum += v, ++n; }
    void Into(std::vector<double>* out) const {
      if (n > 0) out->push_back(sum / n);
    }
  };
  PairedPerProblem out;
  for (const auto& [problem, draws] : by_problem) {
    Mean success, time, cost, cost_solved;
    for (const auto& [repeat, pair] : draws) {
      if (!pair.first || !pair.second) continue;
      const bool su = pair.first->metrics.success, sl = pair.second->metrics.success;
      out.only_learned += sl && !su;
      out.only_uniform += su && !sl;
      success.Add(static_cast<double>(sl) - static_cast<double>(su));
      if (!errored(*pair.first) && !errored(*pair.second))
        time.Add(pair.second->metrics.time_s - pair.first->metrics.time_s);
      if (pair.first->gfcs_cost && pair.second->gfcs_cost) {
        cost.Add(*pair.second->gfcs_cost - *pair.first->gfcs_cost);
        if (su && sl) cost_solved.Add(*pair.second->gfcs_cost - *pair.first->gfcs_cost);
      }
    }
    success.Into(&out.success);
    time.Into(&out.time);
    cost.Into(&out.cost);
    cost_solved.Into(&out.cost_solved);
  }
  return out;
}

std::string EvaluateRun(const ExperimentConfig& c, const std::string& run_dir) {
  const std::string artifact = run_dir + "/" + kGfcsArtifact;
  FS_THROW_UNLESS(fs::exists(artifact), run_dir, ": no ", kGfcsArtifact,
                  " (the run is not finished; continue it with train --resume)");
  log::SetFile(run_dir + "/log.txt");
  std::ostringstream os;
  os << "{\n  \"artifact\": " << JsonString(artifact) << ",\n  \"sets\": [\n";
  for (std::size_t i = 0; i < c.eval.problems.size(); ++i) {
    const manipulation::ProblemsConfig& set = c.eval.problems[i];
    const std::string dir = run_dir + "/eval/" + std::to_string(i) + "_" + SetName(set);
    fs::create_directories(dir);
    log::Info("evaluating on ", SetName(set), " problems ", set.first, "-", set.last, " -> ", dir);
    const manipulation::PlanReport report =
        manipulation::RunPlanExperiment(EvalPlanConfig(c, set, artifact), dir);
    os << "    {\"set\": " << JsonString(SetName(set)) << ", \"first\": " << set.first
       << ", \"last\": " << set.last << ", \"problems\": " << report.problems
       << ", \"repeats\": " << c.eval.repeats
       << ", \"invalid_problems\": " << report.invalid_problems.size()
       << ",\n     \"methods\": [\n";
    for (std::size_t m = 0; m < report.methods.size(); ++m)
      os << "       {\"name\": " << JsonString(report.methods[m].method)
         << ", \"metrics\": " << report.methods[m].summary.ToJson() << "}"
         << (m + 1 < report.methods.size() ? "," : "") << "\n";
    // Paired differences of a sampler against a reference sampler, per budget ("only_learned":
    // solved by the variant only, "only_uniform": by the reference only).
    const auto paired = [&](const std::string& key, const std::string& variant,
                            const std::string& reference) {
      os << "     ],\n     \"" << key << "\": [\n";
      for (std::size_t b = 0; b < c.eval.batches.size(); ++b) {
        const std::string uni = reference + " (" + BudgetLabel(c.eval.batches[b]) + ")";
        const std::string lea = variant + " (" + BudgetLabel(c.eval.batches[b]) + ")";
        const PairedPerProblem pairs = PairPerProblem(report.attempts, uni, lea);
        const std::uint64_t seed = static_cast<std::uint64_t>(c.seed) + 1000 * i + 10 * b;
        const auto stat = [&](const char* name, const std::vector<double>& d, int k) {
          const PairedDifference p = Bootstrap(d, seed + k);
          return std::string("\"") + name + "\": {\"n\": " + std::to_string(p.n) +
                 ", \"mean\": " + Num(p.mean) + ", \"ci95\": [" + Num(p.lo) + ", " + Num(p.hi) +
                 "]";
        };
        os << "       {\"batches\": " << c.eval.batches[b] << ", " << stat("cost_s", pairs.cost, 0)
           << "}, " << stat("cost_both_solved_s", pairs.cost_solved, 1) << "}, "
           << stat("solve_time_s", pairs.time, 2) << "}, " << stat("success", pairs.success, 3)
           << ", \"only_learned\": " << pairs.only_learned
           << ", \"only_uniform\": " << pairs.only_uniform << "}}"
           << (b + 1 < c.eval.batches.size() ? "," : "") << "\n";
      }
    };
    paired("learned_minus_uniform", "GFCS learned", "GFCS uniform");
    if (c.eval.uniform_share > 0)
      paired("mixed_minus_uniform", MixedLabel(c.eval.uniform_share), "GFCS uniform");
    if (c.eval.nearest) {
      paired("nearest_minus_uniform", "GFCS nearest", "GFCS uniform");
      paired("learned_minus_nearest", "GFCS learned", "GFCS nearest");
    }
    os << "     ]}" << (i + 1 < c.eval.problems.size() ? "," : "") << "\n";
  }
  const std::string loop = ReadText(run_dir + "/loop_summary.json");
  os << "  ],\n  \"loop\": "
     << (loop.empty() ? "null" : loop.substr(0, loop.find_last_not_of("\n") + 1)) << "\n}\n";
  WriteFileAtomically(run_dir + "/eval.json", os.str());
  return os.str();
}

}  // namespace foresight::gfcs
