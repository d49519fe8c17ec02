#include "training/diffeo/train.h"

#include <algorithm>
#include <filesystem>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "inference/imitation/metrics.h"
#include "inference/imitation/template_artifact.h"
#include "inference/imitation/transforms.h"
#include "models/imitation/eflow_net.h"
#include "models/imitation/flow_net.h"
#include "training/diffeo/eval_common.h"
#include "training/diffeo/imitation_task.h"
#include "training/trainer.h"

namespace foresight::imitation {
namespace fs = std::filesystem;

namespace {

/// [d x n] -> [n, d] float64.
torch::Tensor Rows(const Eigen::MatrixXd& m) {
  torch::Tensor t = torch::empty({m.cols(), m.rows()}, torch::kFloat64);
  auto a = t.accessor<double, 2>();
  for (Eigen::Index i = 0; i < m.cols(); ++i)
    for (Eigen::Index k = 0; k < m.rows(); ++k) a[i][k] = m(k, i);
  return t;
}

/// The grid of inducing states over the training demonstrations (grown by flow.margin).
template <int D>
RbfGridSpec<D> ShapeGrid(const ExperimentConfig& c, const Eigen::MatrixXd& positions) {
  const Vec<D> lo = positions.rowwise().minCoeff(), hi = positions.rowwise().maxCoeff();
  return RbfGrid<D>::Covering(lo, hi, c.flow.margin, c.flow.spacing, c.flow.gamma,
                              c.flow.cutoff_radius);
}

template <int D>
torch::Tensor Centres(const RbfGridSpec<D>& spec) {
  const RbfGrid<D> grid(spec, "flow grid");
  torch::Tensor t = torch::empty({grid.size(), D}, torch::kFloat64);
  auto a = t.accessor<double, 2>();
  for (int i = 0; i < grid.size(); ++i)
    for (int k = 0; k < D; ++k) a[i][k] = grid.Centre(i)[k];
  return t;
}

/// penalty_lattice^D points over the grid's box (where the flow must stay invertible), [n, D].
template <int D>
torch::Tensor PenaltyLattice(const RbfGridSpec<D>& spec, int per_axis) {
  int total = 1;
  for (int a = 0; a < D; ++a) total *= per_axis;
  torch::Tensor t = torch::empty({total, D}, torch::kFloat64);
  auto acc = t.accessor<double, 2>();
  for (int k = 0; k < total; ++k) {
    int r = k;
    for (int a = 0; a < D; ++a) {
      const double extent = spec.spacing * (spec.counts[static_cast<std::size_t>(a)] - 1);
      acc[k][a] = spec.lower[a] + extent * ((r % per_axis) + 0.5) / per_axis;
      r /= per_axis;
    }
  }
  return t;
}

/// Everything a shape's networks are built from (deterministic in the config and the data).
struct ShapeData {
  Eigen::MatrixXd positions, velocities;  // training demos [d x n]
  torch::Tensor train_x, train_v, val_x, val_v, goal;
  torch::Tensor penalty_points;  // lattice over the flow grid's box
  double initial_speed = 1;
  int dimension = 2;
};

ShapeData Prepare(const ExperimentConfig& c, const PreparedDemos& d) {
  ShapeData s;
  s.dimension = d.demos.dimension;
  StackDemos(d.demos, d.train, &s.positions, &s.velocities);
  const Eigen::Index n = s.positions.cols();
  std::vector<Eigen::Index> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(static_cast<std::uint64_t>(c.seed) + 3);
  std::shuffle(order.begin(), order.end(), rng);
  const Eigen::Index n_val =
      c.val_fraction > 0 ? std::max<Eigen::Index>(1, std::llround(c.val_fraction * n)) : 0;
  FS_THROW_UNLESS(n - n_val >= 1, d.name, ": too few samples to train (", n, ")");
  const auto pick = [&](Eigen::Index from, Eigen::Index to, const Eigen::MatrixXd& m) {
    Eigen::MatrixXd out(m.rows(), to - from);
    for (Eigen::Index i = from; i < to; ++i)
      out.col(i - from) = m.col(order[static_cast<std::size_t>(i)]);
    return out;
  };
  s.val_x = Rows(n_val > 0 ? pick(0, n_val, s.positions) : s.positions);
  s.val_v = Rows(n_val > 0 ? pick(0, n_val, s.velocities) : s.velocities);
  s.train_x = Rows(pick(n_val, n, s.positions));
  s.train_v = Rows(pick(n_val, n, s.velocities));
  s.goal = torch::zeros({s.dimension}, torch::kFloat64);  // normalised: the goal is the origin
  Eigen::VectorXd speeds = s.velocities.colwise().norm();
  std::sort(speeds.data(), speeds.data() + speeds.size());
  s.initial_speed = std::max(1e-6, speeds[speeds.size() / 2]);
  s.penalty_points = s.dimension == 2
                         ? PenaltyLattice<2>(ShapeGrid<2>(c, s.positions), c.flow.penalty_lattice)
                         : PenaltyLattice<3>(ShapeGrid<3>(c, s.positions), c.flow.penalty_lattice);
  return s;
}

/// The flow's training data: `s` with the tube samples of flow.tube_* appended to the training
/// pairs (validation pairs unchanged); `s` itself when tube_sigma is 0. Deterministic in the seed.
ShapeData WithTube(const ExperimentConfig& c, ShapeData s) {
  if (c.flow.tube_sigma <= 0) return s;
  const torch::Tensor x = s.train_x.repeat({c.flow.tube_copies, 1});
  const torch::Tensor v = s.train_v.repeat({c.flow.tube_copies, 1});
  torch::Tensor offset = torch::empty_like(x);
  std::mt19937_64 rng(static_cast<std::uint64_t>(c.seed) + 5);
  std::normal_distribution<double> normal(0.0, c.flow.tube_sigma);
  double* o = offset.data_ptr<double>();
  for (std::int64_t i = 0; i < offset.numel(); ++i) o[i] = normal(rng);
  s.train_x = torch::cat({s.train_x, x + offset});
  s.train_v = torch::cat({s.train_v, v - c.flow.tube_gain * offset});
  return s;
}

template <int D>
RbfFlowNet MakeFlowNet(const ExperimentConfig& c, const ShapeData& s) {
  const RbfGridSpec<D> grid = ShapeGrid<D>(c, s.positions);
  RbfFlowNet net(Centres<D>(grid), c.flow.gamma, c.flow.cutoff_radius, c.flow.time, c.flow.steps,
                 s.initial_speed, c.flow.segments);
  if (!c.flow.autograd)
    net->SetObjective(MakeFlowObjective<D>(grid, c.flow.time, c.flow.steps, c.flow.segments,
                                           RbfFlowNetImpl::kStepLipschitz, kGoalEpsilon));
  return net;
}

RbfFlowNet MakeFlowNet(const ExperimentConfig& c, const ShapeData& s) {
  return s.dimension == 2 ? MakeFlowNet<2>(c, s) : MakeFlowNet<3>(c, s);
}

EFlowNet MakeEflowNet(const ExperimentConfig& c, const ShapeData& s) {
  EFlowNetOptions o;
  o.dimension = s.dimension;
  o.layers = c.eflow.layers;
  o.features = c.eflow.features;
  o.bandwidth = c.eflow.bandwidth;
  o.initial_speed = s.initial_speed;
  o.seed = static_cast<std::uint64_t>(c.seed) + 17;
  return EFlowNet(o);
}

/// Trains one model in `dir`; false when interrupted.
bool TrainModel(std::shared_ptr<VelocityModel> model, const ShapeData& s, const TrainConfig& tc,
                double penalty_weight, const std::string& dir, std::uint64_t seed, bool resume,
                const std::atomic<bool>* interrupt, const std::string& what) {
  ImitationTask task(std::move(model), s.train_x, s.train_v, s.val_x, s.val_v, s.goal,
                     s.penalty_points, penalty_weight);
  RunPaths run{dir};
  fs::create_directories(dir);
  TrainHooks hooks;
  hooks.interrupt = interrupt;
  const TrainingSummary summary =
      Train(&task, tc, run, seed, resume && fs::exists(run.Checkpoint()), hooks);
  log::Info(what, ": ", summary.BriefReport());
  FS_THROW_UNLESS(summary.reason != TerminationReason::kNonFiniteLoss, what,
                  ": the loss became non-finite; lower train.learning_rate or flow.time");
  return summary.reason != TerminationReason::kInterrupted;
}

/// Restart r's config (0 <= r < flow.TotalRestarts()): setting v = r / restarts (0: flow.time and
/// flow.steps, v > 0: flow.alternatives[v - 1]) with seed + 1000 (r % restarts); r = 0 is the
/// run's own config.
ExperimentConfig RestartConfig(const ExperimentConfig& c, int r) {
  ExperimentConfig rc = c;
  const int v = r / c.flow.restarts;
  rc.seed = c.seed + 1000 * (r % c.flow.restarts);
  if (v > 0) {
    rc.flow.time = c.flow.alternatives[static_cast<std::size_t>(v - 1)].time;
    rc.flow.steps = c.flow.alternatives[static_cast<std::size_t>(v - 1)].steps;
  }
  return rc;
}

/// "restart r" for logs and errors, with its flow time and steps when alternatives are trained.
std::string RestartName(const ExperimentConfig& c, int r) {
  std::string out = "restart " + std::to_string(r);
  if (c.flow.alternatives.empty()) return out;
  const ExperimentConfig rc = RestartConfig(c, r);
  std::ostringstream s;
  s << out << " (T " << rc.flow.time << ", K " << rc.flow.steps << ")";
  return s.str();
}

template <int D>
RbfFlow<D> EngineFlow(const ExperimentConfig& c, const PreparedDemos& d, const ShapeData& s,
                      RbfFlowNet& net) {
  const RbfGrid<D> grid(ShapeGrid<D>(c, s.positions), d.name + ": flow grid");
  FlowSettings<D> settings;
  settings.time = c.flow.time;
  settings.steps = c.flow.steps;
  settings.segments = c.flow.segments;
  return RbfFlow<D>(grid, net->WeightsAsEigen(), settings, d.name);
}

/// Invertible where it is used: on the grid's box and at every training sample, to
/// flow.inverse_tolerance plus the loader's allowance (RbfFlow::TruncationAllowance), so an
/// exported flow always loads.
template <int D>
InvertibilityReport Invertibility(const ExperimentConfig& c, const ShapeData& s,
                                  const RbfFlow<D>& flow) {
  const Eigen::Matrix<double, D, Eigen::Dynamic> box = InvertibilityCheckPoints<D>(flow.grid());
  Eigen::Matrix<double, D, Eigen::Dynamic> points(D, box.cols() + s.positions.cols());
  points << box, s.positions;
  return CheckInvertible<D>(flow, points, c.flow.inverse_tolerance + flow.TruncationAllowance());
}

/// The restart to export (train.h, ExportShape): rollouts of each invertible restart's system
/// from the training demonstrations' starts, scored by the mean discrete Frechet distance to
/// those demonstrations (arc-length resampled as the evaluation does).
template <int D>
int ChooseRestart(const ExperimentConfig& c, const PreparedDemos& d, const ShapePaths& paths) {
  if (c.flow.TotalRestarts() == 1) return 0;
  const RolloutSettings roll = ModelRollouts(c);
  int best = -1, first_invertible = -1;
  double best_score = std::numeric_limits<double>::infinity();
  std::ostringstream scores;
  for (int r = 0; r < c.flow.TotalRestarts(); ++r) {
    const ExperimentConfig rc = RestartConfig(c, r);
    const ShapeData s = Prepare(rc, d);
    RbfFlowNet net = MakeFlowNet(rc, s);
    const std::string checkpoint = RunPaths{paths.FlowDir(r)}.BestCheckpoint();
    FS_THROW_UNLESS(fs::exists(checkpoint), d.name, ": ", checkpoint,
                    " is missing; train the run first");
    LoadCheckpointModel(checkpoint, net.get());
    const RbfFlow<D> flow = EngineFlow<D>(rc, d, s, net);
    scores << (r ? ", " : "")
           << (c.flow.alternatives.empty() ? std::to_string(r) : RestartName(c, r)) << ": ";
    if (!Invertibility<D>(rc, s, flow).ok) {
      scores << "not invertible";
      continue;
    }
    if (first_invertible < 0) first_invertible = r;
    const ImitationSystem<D> system(flow, Vec<D>::Zero(), net->speed());
    FlowWorkspace<D> ws = system.flow().MakeWorkspace();
    const auto velocity = [&](const Vec<D>& x) { return system.Velocity(x, &ws); };
    double sum = 0;
    for (const int i : d.train) {
      const Eigen::MatrixXd& demo = d.demos.demos[static_cast<std::size_t>(i)].position;
      const Rollout<D> path = RollOut<D>(velocity, demo.col(0), Vec<D>::Zero(), roll);
      sum += path.finite ? DiscreteFrechet(ResampleByArcLength(path.path, c.eval.resample),
                                           ResampleByArcLength(demo, c.eval.resample))
                         : std::numeric_limits<double>::infinity();
    }
    const double score = sum / static_cast<double>(d.train.size());
    scores << score;
    if (score < best_score) {
      best_score = score;
      best = r;
    }
  }
  FS_THROW_UNLESS(first_invertible >= 0, d.name, ": none of the ", c.flow.TotalRestarts(),
                  " restarts' flows is invertible (flow.time ", c.flow.time, ", flow.steps ",
                  c.flow.steps, c.flow.alternatives.empty() ? "" : " and flow.alternatives",
                  "); use more flow.steps or a shorter flow.time");
  if (best <
      0) {  // every invertible restart's rollouts diverged: as a single run would, export one
    best = first_invertible;
    log::Warn(d.name, ": every invertible restart's rollout from a training start diverged");
  }
  log::Info(d.name, ": flow restarts, mean Frechet from the training starts {", scores.str(),
            "}: exporting ", RestartName(c, best));
  return best;
}

/// Exports restart config `rc`'s trained flow; the artifact keeps the run's config `c`.
template <int D>
void ExportFlow(const ExperimentConfig& c, const ExperimentConfig& rc, const PreparedDemos& d,
                const ShapeData& s, RbfFlowNet& net, const std::string& path) {
  const RbfFlow<D> flow = EngineFlow<D>(rc, d, s, net);
  const InvertibilityReport report = Invertibility<D>(rc, s, flow);
  FS_THROW_UNLESS(report.ok, d.name, ": the trained flow is not invertible with flow.time ",
                  rc.flow.time, " and flow.steps ", rc.flow.steps, " (", report.Describe(),
                  "); use more flow.steps or a shorter flow.time");
  const ImitationSystem<D> system(flow, Vec<D>::Zero(), net->speed());
  TemplateNormalisation norm;
  norm.offset = d.norm.offset;
  norm.scale = d.norm.scale;
  SaveTemplate<D>(path, system, norm, config::ToYaml(c), c.seed);
}

}  // namespace

bool ShapeExported(const ExperimentConfig& c, const ShapePaths& paths) {
  return fs::exists(paths.Template()) && (!c.eflow.enabled || fs::exists(paths.Eflow()));
}

bool TrainShape(const ExperimentConfig& c, const PreparedDemos& demos, const ShapePaths& paths,
                bool resume, const std::atomic<bool>* interrupt) {
  for (int r = 0; r < c.flow.TotalRestarts(); ++r) {
    const ExperimentConfig rc = RestartConfig(c, r);
    const ShapeData rs = Prepare(rc, demos);
    RbfFlowNet flow = MakeFlowNet(rc, rs);
    if (!TrainModel(
            flow.ptr(), WithTube(rc, rs), c.train, c.flow.invertibility_weight, paths.FlowDir(r),
            static_cast<std::uint64_t>(rc.seed), resume, interrupt,
            demos.name + " flow" + (c.flow.TotalRestarts() > 1 ? " " + RestartName(c, r) : "")))
      return false;
  }
  if (!c.eflow.enabled) return true;
  const ShapeData s = Prepare(c, demos);
  const auto seed = static_cast<std::uint64_t>(c.seed);
  EFlowNet eflow = MakeEflowNet(c, s);
  return TrainModel(eflow.ptr(), s, c.eflow.train, 0.0, paths.EflowDir(), seed + 1, resume,
                    interrupt, demos.name + " eflow");
}

void ExportShape(const ExperimentConfig& c, const PreparedDemos& demos, const ShapePaths& paths) {
  const int restart = demos.demos.dimension == 2 ? ChooseRestart<2>(c, demos, paths)
                                                 : ChooseRestart<3>(c, demos, paths);
  const ExperimentConfig rc = RestartConfig(c, restart);
  const ShapeData rs = Prepare(rc, demos);
  fs::create_directories(fs::path(paths.Template()).parent_path());
  RbfFlowNet flow = MakeFlowNet(rc, rs);
  const std::string best = RunPaths{paths.FlowDir(restart)}.BestCheckpoint();
  FS_THROW_UNLESS(fs::exists(best), demos.name, ": ", best, " is missing; train the run first");
  LoadCheckpointModel(best, flow.get());
  if (rs.dimension == 2)
    ExportFlow<2>(c, rc, demos, rs, flow, paths.Template());
  else
    ExportFlow<3>(c, rc, demos, rs, flow, paths.Template());
  if (!c.eflow.enabled) return;
  const ShapeData s = Prepare(c, demos);
  EFlowNet eflow = MakeEflowNet(c, s);
  const std::string ebest = RunPaths{paths.EflowDir()}.BestCheckpoint();
  FS_THROW_UNLESS(fs::exists(ebest), demos.name, ": ", ebest, " is missing; train the run first");
  LoadCheckpointModel(ebest, eflow.get());
  eflow->ToEngine(Eigen::VectorXd::Zero(s.dimension))
      .Save(paths.Eflow(), config::ToYaml(c), c.seed);
}

}  // namespace foresight::imitation
