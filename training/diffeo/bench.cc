// The diffeo kind's bench (`foresight bench RUN_DIR|ARTIFACT`): time of one velocity evaluation
// (one rollout step) of diffeomorphic templates, measured side by side in one run on one thread,
// medians of repeated runs: the imitation system alone (engine vs LibTorch on the same weights),
// composed with an obstacle transform (2-D artifacts), and the JACO arm's C-space system with and
// without the C-space obstacle transform (3-D artifacts; needs kinova_jaco_j2n6s300 in the data
// root). A benchmark that prints figures, not a test.

#include "core/bench.h"

#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <random>
#include <sstream>

#include "core/error.h"
#include "datasets/data_root.h"
#include "inference/imitation/cspace.h"
#include "inference/imitation/template_artifact.h"
#include "inference/imitation/transforms.h"
#include "models/imitation/flow_net.h"
#include "models/imitation/occupancy_fit.h"
#include "training/diffeo/config.h"
#include "training/kinds.h"

namespace foresight::imitation {
namespace {

struct DiffeoBenchOptions {
  std::string data_root;
  int calls = 2000;
  int repeats = 7;
  double table_spacing = 0.004;  ///< configs/diffeo/lasa.yaml's obstacle.map_table_spacing

  template <class A>
  void Serialize(A* a) {
    a->Visit("data_root", &data_root, config::Range::Any(),
             "data root for the JACO URDF of 3-D artifacts (empty: $FORESIGHT_DATA, else "
             "../shared/data)");
    a->Visit("calls", &calls, config::Range::Closed(10, 10000000), "calls per timed run");
    a->Visit("repeats", &repeats, config::Range::Closed(1, 100), "timed runs (median reported)");
    a->Visit(
        "table_spacing", &table_spacing, config::Range::Positive(),
        "2-D: node spacing of the tabulated obstacle map's row (as obstacle.map_table_spacing)");
  }
};

/// Median over `repeats` of the mean time (us) of `calls` calls of f(i), after a warm-up.
template <class F>
double MicrosPerCall(const DiffeoBenchOptions& a, F&& f) {
  for (int i = 0; i < std::min(200, a.calls); ++i) f(i);
  return 1e6 * bench::SecondsPerCall(a.repeats, a.calls, f);
}

/// Points spread over the grid's box (the region the template was trained on).
template <int D>
std::vector<Vec<D>> Points(const RbfGrid<D>& grid, int n) {
  std::mt19937_64 rng(1);
  const Vec<D> lo = grid.spec().lower;
  Vec<D> hi = lo;
  for (int a = 0; a < D; ++a) hi[a] += grid.spec().spacing * (grid.spec().counts[a] - 1);
  std::vector<Vec<D>> out;
  for (int i = 0; i < n; ++i) {
    Vec<D> p;
    for (int a = 0; a < D; ++a)
      p[a] = std::uniform_real_distribution<double>(lo[a] + 0.1 * (hi[a] - lo[a]),
                                                    hi[a] - 0.1 * (hi[a] - lo[a]))(rng);
    out.push_back(p);
  }
  return out;
}

/// The LibTorch net with the artifact's weights (the trainer's module).
template <int D>
RbfFlowNet TorchNet(const ImitationSystem<D>& s) {
  const RbfGrid<D>& grid = s.flow().grid();
  torch::Tensor centres = torch::empty({grid.size(), D}, torch::kFloat64);
  for (int i = 0; i < grid.size(); ++i)
    for (int k = 0; k < D; ++k) centres[i][k] = grid.Centre(i)[k];
  RbfFlowNet net(centres, grid.gamma(), grid.spec().cutoff_radius, s.flow().settings().time,
                 s.flow().settings().steps, s.speed(), s.flow().settings().segments);
  torch::NoGradGuard no_grad;
  const Eigen::MatrixXd& w = s.flow().weights();
  for (Eigen::Index i = 0; i < w.rows(); ++i)
    for (Eigen::Index k = 0; k < w.cols(); ++k) net->weights[i][k] = w(i, k);
  return net;
}

struct Row {
  std::string name;
  double micros = 0;
  std::string note;
};

template <int D>
std::vector<Row> Imitation(const DiffeoBenchOptions& a, const ImitationSystem<D>& s) {
  const auto pts = Points<D>(s.flow().grid(), 256);
  FlowWorkspace<D> ws = s.flow().MakeWorkspace();
  Vec<D> sink = Vec<D>::Zero();
  const double engine = MicrosPerCall(a, [&](int i) { sink += s.Velocity(pts[i % 256], &ws); });
  RbfFlowNet net = TorchNet<D>(s);
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> xs;
  for (const Vec<D>& p : pts) {
    torch::Tensor t = torch::empty({1, D}, torch::kFloat64);
    for (int k = 0; k < D; ++k) t[0][k] = p[k];
    xs.push_back(t);
  }
  const torch::Tensor goal = torch::zeros({D}, torch::kFloat64);
  DiffeoBenchOptions fewer = a;
  fewer.calls = std::max(50, a.calls / 10);
  const double libtorch = MicrosPerCall(
      fewer, [&](int i) { (void)net->Velocity(xs[static_cast<std::size_t>(i % 256)], goal); });
  std::ostringstream note;
  note << "K = " << s.flow().settings().steps << " Euler steps, " << s.flow().grid().size()
       << " inducing states";
  (void)sink;
  return {{"imitation step, engine", engine, note.str()},
          {"imitation step, LibTorch (batch 1)", libtorch, "same weights, no autograd"}};
}

/// One step of the composed 2-D system, the obstacle map (ObstacleConfig's default map settings)
/// evaluated exactly and through a bicubic table with nodes `table_spacing` apart (by default the
/// LASA config's obstacle.map_table_spacing), same flow and points.
std::vector<Row> Composed2d(const DiffeoBenchOptions& a, const ImitationSystem<2>& s,
                            double table_spacing) {
  // A disc between the middle of the grid and the goal, mapped as the evaluation does.
  const ObstacleConfig o;
  const RbfGrid<2>& g = s.flow().grid();
  Vec<2> mid = g.spec().lower;
  for (int k = 0; k < 2; ++k) mid[k] += 0.5 * g.spec().spacing * (g.spec().counts[k] - 1);
  const Vec<2> centre = 0.5 * (mid + s.goal());
  const double r = o.radius;
  Eigen::Matrix<double, 2, Eigen::Dynamic> pts;
  std::vector<std::uint8_t> occ;
  SampleObstacleOccupancy<2>([&](const Vec<2>& p) { return (p - centre).norm() - r; },
                             centre.array() - r - o.sample_margin,
                             centre.array() + r + o.sample_margin, o.sample_spacing, &pts, &occ);
  const RbfGrid<2> mg(RbfGrid<2>::Covering(centre.array() - r - o.sample_margin,
                                           centre.array() + r + o.sample_margin, 0, o.map_spacing,
                                           o.map_gamma, o.map_cutoff),
                      "bench map");
  const OccupancyField<2> field = FitOccupancyField<2>(mg, pts, occ, o.map_l2, "bench map");
  OccupancyField<2> table = field;
  table.Tabulate(table_spacing, "bench map");
  std::vector<Vec<2>> near;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-3 * r, 3 * r);
  for (int i = 0; i < 256; ++i) near.push_back(centre + Vec<2>(u(rng), u(rng)));
  const auto step_us = [&](const OccupancyField<2>& map) {
    OuterTransform<2> t;
    t.type = OuterTransform<2>::Type::kObstacle;
    FlowSettings<2> fs;
    fs.time = 0.008;
    fs.steps = 16;
    t.obstacle = ObstacleTransform<2>(map, fs);
    const ComposedSystem<2> sys(s, {t});
    auto ws = sys.MakeWorkspace();
    Vec<2> sink = Vec<2>::Zero();
    const double us = MicrosPerCall(a, [&](int i) { sink += sys.Velocity(near[i % 256], &ws); });
    (void)sink;
    return us;
  };
  std::ostringstream tabulated;
  tabulated << "the same, the map through its bicubic table (nodes " << table_spacing << " apart)";
  return {{"composed step (imitation + obstacle), engine", step_us(field),
           "obstacle flow 16 Euler steps, queries within 3 radii of the disc"},
          {"composed step, tabulated obstacle map, engine", step_us(table), tabulated.str()}};
}

std::vector<Row> CSpace(const DiffeoBenchOptions& a, const TemplateArtifact<3>& art) {
  const std::string dir = ResolveDataFile(a.data_root, "kinova_jaco_j2n6s300");
  if (!std::filesystem::exists(dir)) return {{"C-space step", -1, "skipped: no " + dir}};
  const SerialChain chain = SerialChain::LoadJaco(dir);
  TaskNormalisation tn;
  tn.offset = art.normalisation.offset;
  tn.scale = art.normalisation.scale;
  // End-effector targets over the template's region, reached by IK: configurations where the
  // imitation system and the obstacle are both active (a random configuration is mostly neither).
  const auto targets = Points<3>(art.system.flow().grid(), 64);
  // A 15 cm ball's map at the middle of those targets, for timing.
  const ObstacleConfig o;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Vec<3>& t : targets) centre += tn.ToWorld(t) / static_cast<double>(targets.size());
  const double r = 0.075, margin = 0.1, spacing = 0.05;
  Eigen::Matrix<double, 3, Eigen::Dynamic> pts;
  std::vector<std::uint8_t> occ;
  SampleObstacleOccupancy<3>([&](const Vec<3>& p) { return (p - centre).norm() - r; },
                             centre.array() - r - margin, centre.array() + r + margin, 0.02, &pts,
                             &occ);
  const RbfGrid<3> mg(RbfGrid<3>::Covering(centre.array() - r - margin, centre.array() + r + margin,
                                           0, spacing, 300, 0.12),
                      "bench map");
  const OccupancyField<3> field = FitOccupancyField<3>(mg, pts, occ, o.map_l2, "bench map");
  FlowSettings<kArmDof> fs;
  fs.time = 0.02;
  fs.steps = 10;
  const CSpaceSystem plain(chain, art.system, tn);
  const CSpaceSystem avoid(chain, art.system, tn, CSpaceObstacleTransform(chain, field, fs));
  std::vector<ArmVector> qs;
  ArmVector seed_q;
  seed_q << 0, 3.6, 1.4, 0, 1.0, 0;  // as the evaluation's IK
  for (const Vec<3>& t : targets) {
    ArmVector q;
    if (InverseKinematics(chain, tn.ToWorld(t), seed_q, &q, 1e-4, 300)) qs.push_back(q);
  }
  FS_THROW_UNLESS(!qs.empty(), "bench: the arm reaches none of the template's region");
  auto w1 = plain.MakeWorkspace();
  auto w2 = avoid.MakeWorkspace();
  ArmVector sink = ArmVector::Zero();
  const int nq = static_cast<int>(qs.size());
  const double t_plain = MicrosPerCall(a, [&](int i) { sink += plain.Velocity(qs[i % nq], &w1); });
  const double t_avoid = MicrosPerCall(a, [&](int i) { sink += avoid.Velocity(qs[i % nq], &w2); });
  (void)sink;
  std::ostringstream note;
  note << chain.num_points() << " body points, obstacle flow 10 Euler steps, " << nq
       << " configurations reaching the template's region";
  return {{"C-space step (pull-back only), engine", t_plain, "J_ee pseudo-inverse"},
          {"C-space step (with obstacle transform), engine", t_avoid, note.str()}};
}

void RunDiffeoBench(const BenchRequest& req, const DiffeoBenchOptions& a) {
  torch::set_num_threads(1);
  const std::string artifact = BenchArtifact(req, "models/");
  const int d = TemplateDimension(artifact);
  std::vector<Row> rows;
  if (d == 2) {
    const TemplateArtifact<2> art = LoadTemplate<2>(artifact);
    rows = Imitation<2>(a, art.system);
    for (const Row& r : Composed2d(a, art.system, a.table_spacing)) rows.push_back(r);
  } else {
    const TemplateArtifact<3> art = LoadTemplate<3>(artifact);
    rows = Imitation<3>(a, art.system);
    for (const Row& r : CSpace(a, art)) rows.push_back(r);
  }
  const double ratio = rows[1].micros / rows[0].micros;
  if (req.json) {
    std::cout << "{\"artifact\": \"" << artifact << "\", \"dimension\": " << d
              << ", \"engine_vs_libtorch_speedup\": " << ratio << ", \"steps_us\": {";
    for (std::size_t i = 0; i < rows.size(); ++i)
      std::cout << (i ? ", " : "") << "\"" << rows[i].name << "\": " << rows[i].micros;
    std::cout << "}}\n";
    return;
  }
  std::cout << "one rollout step (one velocity), one thread, median of " << a.repeats << " runs:\n";
  for (const Row& r : rows)
    std::cout << "  " << r.name << ": "
              << (r.micros < 0 ? std::string("-") : std::to_string(r.micros)) << " us  (" << r.note
              << ")\n";
  std::cout << "  engine vs LibTorch (imitation): " << ratio << "x\n";
}

}  // namespace

void SetBenchStep(ExperimentKind* kind) { SetBench<DiffeoBenchOptions>(kind, RunDiffeoBench); }

}  // namespace foresight::imitation
