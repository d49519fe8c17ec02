#include "inference/manipulation/energy_model.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <numeric>
#include <thread>

#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight::manipulation {
namespace {

// Eigen's GEMM kernel with caller-owned cache-blocking buffers: the public product API allocates
// (malloc) its packing buffers on every call above EIGEN_STACK_ALLOCATION_LIMIT (128 KB).
using BlockingSpace =
    Eigen::internal::gemm_blocking_space<Eigen::ColMajor, float, float, Eigen::Dynamic,
                                         Eigen::Dynamic, Eigen::Dynamic, 1, false>;

/// res [rows x cols, column stride res_stride] += lhs [rows x depth] * rhs [depth x cols];
/// lhs is column-major (LhsOrder = ColMajor) or the transpose of a column-major matrix
/// (RowMajor), rhs and res column-major.
template <int LhsOrder>
void GemmAccumulate(Eigen::Index rows, Eigen::Index cols, Eigen::Index depth, const float* lhs,
                    Eigen::Index lhs_stride, const float* rhs, Eigen::Index rhs_stride, float* res,
                    Eigen::Index res_stride, BlockingSpace* blocking) {
  Eigen::internal::general_matrix_matrix_product<Eigen::Index, float, LhsOrder, false, float,
                                                 Eigen::ColMajor, false, Eigen::ColMajor,
                                                 1>::run(rows, cols, depth, lhs, lhs_stride, rhs,
                                                         rhs_stride, res, 1, res_stride, 1.0f,
                                                         *blocking, nullptr);
}

bool AllFinite(const Mlp& mlp) {
  for (const auto& l : mlp.layers())
    if (!l.weight.allFinite() || !l.bias.allFinite()) return false;
  return true;
}

std::vector<std::string> LayerNames(int n) {
  std::vector<std::string> names;
  for (int i = 0; i < n; ++i) names.push_back("linear" + std::to_string(i));
  return names;
}

}  // namespace

struct EnergyModel::Workspace::Blocking {
  BlockingSpace space;
};
EnergyModel::Workspace::Workspace() = default;
EnergyModel::Workspace::Workspace(Workspace&&) noexcept = default;
EnergyModel::Workspace& EnergyModel::Workspace::operator=(Workspace&&) noexcept = default;
EnergyModel::Workspace::~Workspace() = default;

EnergyModel::EnergyModel(EnergyModelParts parts) : parts_(std::move(parts)) {
  const EnergyModelParts& p = parts_;
  p.lattice.Validate("EnergyModel");
  const int n_r = p.lattice.size();
  FS_THROW_UNLESS(p.intermediate_commands >= 1, "EnergyModel: intermediate_commands ",
                  p.intermediate_commands, " must be at least 1");
  FS_THROW_UNLESS(std::isfinite(p.velocity_scale) && p.velocity_scale > 0,
                  "EnergyModel: velocity_scale ", p.velocity_scale, " must be finite and positive");
  FS_THROW_UNLESS(
      p.lower.allFinite() && p.upper.allFinite() && (p.lower.array() < p.upper.array()).all(),
      "EnergyModel: joint limits must be finite with lower < upper (lower ", p.lower.transpose(),
      ", upper ", p.upper.transpose(), ")");
  FS_THROW_UNLESS(p.bps_mean.size() == n_r, "EnergyModel: bps_mean has ", p.bps_mean.size(),
                  " entries for a lattice of N_R = ", n_r, " points");
  FS_THROW_UNLESS(p.bps_std.size() == n_r, "EnergyModel: bps_std has ", p.bps_std.size(),
                  " entries for a lattice of N_R = ", n_r, " points");
  FS_THROW_UNLESS(p.bps_mean.allFinite() && p.bps_std.allFinite() && (p.bps_std.array() > 0).all(),
                  "EnergyModel: bps_mean must be finite and bps_std finite and positive");
  FS_THROW_UNLESS(!p.encoder.layers().empty(), "EnergyModel: the encoder has no layers");
  FS_THROW_UNLESS(!p.energy.layers().empty(), "EnergyModel: the energy network has no layers");
  FS_THROW_UNLESS(p.encoder.input_size() == n_r, "EnergyModel: the encoder takes ",
                  p.encoder.input_size(), " inputs but the lattice has N_R = ", n_r, " points");
  const int expected_in = context_size() + command_size();
  FS_THROW_UNLESS(p.energy.input_size() == expected_in, "EnergyModel: the energy network takes ",
                  p.energy.input_size(), " inputs, expected context ", context_size(), " (21 + ",
                  encoding_size(), " encoding) + commands ", command_size(), " (7 x ",
                  p.intermediate_commands, ") = ", expected_in);
  FS_THROW_UNLESS(p.energy.output_size() == 1, "EnergyModel: the energy network gives ",
                  p.energy.output_size(), " outputs, expected 1");
  FS_THROW_UNLESS(AllFinite(p.encoder), "EnergyModel: the encoder has non-finite weights");
  FS_THROW_UNLESS(AllFinite(p.energy), "EnergyModel: the energy network has non-finite weights");
  for (const auto& l : p.energy.layers())
    max_width_ = std::max(max_width_, static_cast<int>(l.weight.rows()));
  ValidateMemory();
}

void EnergyModel::ValidateMemory() const {
  const SolutionMemory& m = parts_.memory;
  const Eigen::Index s = m.problem.size();
  if (s == 0 && m.contexts.cols() == 0 && m.commands.cols() == 0 && m.cost.size() == 0) return;
  FS_THROW_UNLESS(s > 0, "EnergyModel: the solution memory has contexts but no solutions");
  FS_THROW_UNLESS(m.contexts.rows() == context_size() && m.contexts.cols() > 0,
                  "EnergyModel: the solution memory's contexts are ", m.contexts.rows(), " x ",
                  m.contexts.cols(), ", expected ", context_size(), " rows (the model's context)");
  FS_THROW_UNLESS(
      m.commands.rows() == command_size() && m.commands.cols() == s && m.cost.size() == s,
      "EnergyModel: the solution memory has ", s, " solutions but commands ", m.commands.rows(),
      " x ", m.commands.cols(), " (expected ", command_size(), " x ", s, ") and ", m.cost.size(),
      " costs");
  FS_THROW_UNLESS(m.problem.minCoeff() >= 0 && m.problem.maxCoeff() < m.contexts.cols(),
                  "EnergyModel: a solution of the memory names problem ",
                  m.problem.minCoeff() < 0 ? m.problem.minCoeff() : m.problem.maxCoeff(),
                  ", outside its ", m.contexts.cols(), " contexts");
  FS_THROW_UNLESS(m.contexts.allFinite() && m.cost.allFinite(),
                  "EnergyModel: the solution memory has non-finite contexts or costs");
  FS_THROW_UNLESS(m.commands.allFinite() && m.commands.cwiseAbs().maxCoeff() <= 1.0f,
                  "EnergyModel: the solution memory's commands must be finite and in [-1, 1]");
}

EnergyModel EnergyModel::Load(const std::string& artifact_path) {
  const Artifact art = Artifact::Open(artifact_path, kEnergyModelType);
  const h5::File& f = art.file();
  const std::string& path = f.path();
  EnergyModelParts p;
  p.intermediate_commands = art.IntAttr("/model", "intermediate_commands", 1, 1000);
  p.velocity_scale = art.DoubleAttr("/model", "velocity_scale", 1e-12, 1e12);
  p.lattice.spacing = art.DoubleAttr("/model", "bps_spacing", 1e-6, 1e6);
  p.lattice.max_distance = art.DoubleAttr("/model", "bps_max_distance", 1e-9, 1e9);
  p.lattice.lower = f.ReadMatrixD("/model/bps_lower", 3, 1).col(0);
  p.lattice.upper = f.ReadMatrixD("/model/bps_upper", 3, 1).col(0);
  p.lower = f.ReadMatrixD("/model/joint_lower", kDof, 1).col(0);
  p.upper = f.ReadMatrixD("/model/joint_upper", kDof, 1).col(0);
  p.bps_mean = f.ReadMatrixF("/normalisation/bps_mean", -1, 1).col(0);
  p.bps_std = f.ReadMatrixF("/normalisation/bps_std", -1, 1).col(0);
  const int encoder_layers = art.IntAttr("/model", "encoder_layers", 1, 100);
  const int energy_layers = art.IntAttr("/model", "energy_layers", 1, 100);
  p.encoder = Mlp::Load(f, "/weights/encoder/", LayerNames(encoder_layers));
  p.energy = Mlp::Load(f, "/weights/energy/", LayerNames(energy_layers));
  if (f.Exists("/memory")) {
    SolutionMemory& m = p.memory;
    m.contexts = f.ReadMatrixF("/memory/contexts").transpose();
    m.commands = f.ReadMatrixF("/memory/commands").transpose();
    m.cost = f.ReadMatrixF("/memory/cost", -1, 1).col(0);
    const h5::Array<std::int64_t> problem = f.ReadInt("/memory/problem");
    FS_THROW_UNLESS(problem.shape.size() == 1, path, ": /memory/problem must be 1-D");
    m.problem.resize(static_cast<Eigen::Index>(problem.Size()));
    for (std::size_t i = 0; i < problem.Size(); ++i) {
      FS_THROW_UNLESS(problem.data[i] >= 0 && problem.data[i] < (1 << 30), path,
                      ": /memory/problem[", i, "] = ", problem.data[i], " is out of range");
      m.problem[static_cast<Eigen::Index>(i)] = static_cast<int>(problem.data[i]);
    }
  }
  try {
    return EnergyModel(std::move(p));
  } catch (const Error& e) {
    Fail(path, ": ", e.what());
  }
}

void EnergyModel::Save(const std::string& path, const std::string& config_yaml,
                       std::int64_t seed) const {
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, kEnergyModelType, config_yaml, seed);
    const EnergyModelParts& p = parts_;
    f->SetAttr("/model", "intermediate_commands",
               static_cast<std::int64_t>(p.intermediate_commands));
    f->SetAttr("/model", "velocity_scale", p.velocity_scale);
    f->SetAttr("/model", "bps_spacing", p.lattice.spacing);
    f->SetAttr("/model", "bps_max_distance", p.lattice.max_distance);
    f->SetAttr("/model", "encoder_layers", static_cast<std::int64_t>(p.encoder.layers().size()));
    f->SetAttr("/model", "energy_layers", static_cast<std::int64_t>(p.energy.layers().size()));
    f->Write("/model/bps_lower", p.lattice.lower.data(), {3});
    f->Write("/model/bps_upper", p.lattice.upper.data(), {3});
    f->Write("/model/joint_lower", p.lower.data(), {static_cast<std::size_t>(kDof)});
    f->Write("/model/joint_upper", p.upper.data(), {static_cast<std::size_t>(kDof)});
    const auto n_r = static_cast<std::size_t>(p.bps_mean.size());
    f->Write("/normalisation/bps_mean", p.bps_mean.data(), {n_r});
    f->Write("/normalisation/bps_std", p.bps_std.data(), {n_r});
    p.encoder.Save(f, "/weights/encoder/", LayerNames(static_cast<int>(p.encoder.layers().size())));
    p.energy.Save(f, "/weights/energy/", LayerNames(static_cast<int>(p.energy.layers().size())));
    if (!p.memory.empty()) {
      f->WriteMatrix("/memory/contexts", p.memory.contexts.transpose());
      f->WriteMatrix("/memory/commands", p.memory.commands.transpose());
      const std::vector<std::int64_t> problem(p.memory.problem.data(),
                                              p.memory.problem.data() + p.memory.problem.size());
      f->Write("/memory/problem", problem.data(), {problem.size()});
      f->Write("/memory/cost", p.memory.cost.data(),
               {static_cast<std::size_t>(p.memory.cost.size())});
    }
  });
}

EnergyModel::Workspace EnergyModel::MakeWorkspace(int max_particles) const {
  FS_THROW_UNLESS(max_particles >= 1, "EnergyModel::MakeWorkspace: max_particles ", max_particles,
                  " must be at least 1");
  Workspace ws;
  ws.max_particles = max_particles;
  const auto& layers = parts_.energy.layers();
  ws.first = Eigen::VectorXf::Zero(layers.front().weight.rows());
  for (std::size_t i = 0; i + 1 < layers.size(); ++i)
    ws.hidden.push_back(Eigen::MatrixXf::Zero(layers[i].weight.rows(), max_particles));
  ws.delta_a = Eigen::MatrixXf::Zero(max_width_, max_particles);
  ws.delta_b = Eigen::MatrixXf::Zero(max_width_, max_particles);
  // One blocking buffer sized for the largest product of the forward and backward passes.
  const Eigen::Index rows = std::max(max_width_, command_size());
  const Eigen::Index depth = std::max(max_width_, command_size());
  ws.blocking = std::make_unique<Workspace::Blocking>(
      Workspace::Blocking{BlockingSpace(rows, max_particles, depth, 1, true)});
  ws.blocking->space.allocateAll();
  return ws;
}

Eigen::VectorXf EnergyModel::EncodeWorld(const World& world) const {
  const Eigen::VectorXf d = EncodeBps(world, parts_.lattice);
  const Eigen::VectorXf x = (d - parts_.bps_mean).cwiseQuotient(parts_.bps_std);
  Mlp::Workspace ws = parts_.encoder.MakeWorkspace();
  return parts_.encoder.Forward(x, &ws);
}

void EnergyModel::Context(const GfcsQuery& q, const Eigen::VectorXf& encoding,
                          Eigen::VectorXf* context) const {
  FS_THROW_UNLESS(encoding.size() == encoding_size(), "EnergyModel::Context: the encoding has ",
                  encoding.size(), " entries, the model's encoder gives ", encoding_size());
  if (context->size() != context_size()) context->resize(context_size());
  context->segment<kDof>(0) = Normalise(q.start).cast<float>();
  context->segment<kDof>(kDof) = (q.start_velocity / parts_.velocity_scale).cast<float>();
  context->segment<kDof>(2 * kDof) = Normalise(q.goal).cast<float>();
  context->tail(encoding_size()) = encoding;
}

void EnergyModel::EnergyAndGradient(const Eigen::VectorXf& context,
                                    const Eigen::Ref<const Eigen::MatrixXf>& u,
                                    Eigen::VectorXf* energy, Eigen::MatrixXf* grad,
                                    Workspace* ws) const {
  const int ctx = context_size(), du = command_size();
  const auto P = u.cols();
  FS_THROW_UNLESS(context.size() == ctx, "EnergyModel::EnergyAndGradient: the context has ",
                  context.size(), " entries, expected ", ctx);
  FS_THROW_UNLESS(u.rows() == du, "EnergyModel::EnergyAndGradient: u has ", u.rows(),
                  " rows, expected 7 x ", parts_.intermediate_commands, " = ", du);
  FS_THROW_UNLESS(ws->blocking && P <= ws->max_particles, "EnergyModel::EnergyAndGradient: ", P,
                  " particles for a workspace made for ", ws->max_particles);
  if (energy->size() != P) energy->resize(P);
  if (grad && (grad->rows() != du || grad->cols() != P)) grad->resize(du, P);
  if (P == 0) return;
  BlockingSpace* blocking = &ws->blocking->space;
  const auto& layers = parts_.energy.layers();
  const std::size_t L = layers.size();

  // Forward. Layer 0: the context part once, then the commands for every particle.
  const Eigen::MatrixXf& W0 = layers[0].weight;
  const auto w0 = W0.rows();
  ws->first.noalias() = W0.leftCols(ctx) * context;
  ws->first += layers[0].bias;
  for (std::size_t i = 0; i < L; ++i) {
    const DenseLayer& layer = layers[i];
    const auto rows = layer.weight.rows();
    float* out = i + 1 < L ? ws->hidden[i].data() : energy->data();
    const auto out_stride = i + 1 < L ? ws->hidden[i].rows() : 1;
    Eigen::Map<Eigen::MatrixXf, 0, Eigen::OuterStride<>> o(out, rows, P,
                                                           Eigen::OuterStride<>(out_stride));
    if (i == 0) {
      o.colwise() = ws->first;
      GemmAccumulate<Eigen::ColMajor>(rows, P, du, W0.data() + ctx * w0, w0, u.data(),
                                      u.outerStride(), out, out_stride, blocking);
    } else {
      const Eigen::MatrixXf& in = ws->hidden[i - 1];
      o.colwise() = layer.bias;
      GemmAccumulate<Eigen::ColMajor>(rows, P, layer.weight.cols(), layer.weight.data(), rows,
                                      in.data(), in.rows(), out, out_stride, blocking);
    }
    if (i + 1 < L) o = o.cwiseMax(0.0f);
  }
  if (!grad) return;

  // Backward: g = dE/d(pre-activation of layer i), from g = 1 at the output.
  if (L == 1) {
    for (Eigen::Index p = 0; p < P; ++p) grad->col(p) = W0.block(0, ctx, 1, du).transpose();
    return;
  }
  Eigen::MatrixXf* g = &ws->delta_a;
  Eigen::MatrixXf* g_next = &ws->delta_b;
  {
    const Eigen::MatrixXf& h = ws->hidden[L - 2];
    const auto w = h.rows();
    const auto last = layers[L - 1].weight.row(0).transpose();
    for (Eigen::Index p = 0; p < P; ++p)
      g->col(p).head(w) = (h.col(p).array() > 0.0f).select(last.array(), 0.0f);
  }
  for (std::size_t i = L - 2; i >= 1; --i) {  // g holds layer i's; make layer i-1's
    const Eigen::MatrixXf& W = layers[i].weight;
    const Eigen::MatrixXf& h = ws->hidden[i - 1];
    const auto in = W.cols(), out = W.rows();
    g_next->topLeftCorner(in, P).setZero();
    GemmAccumulate<Eigen::RowMajor>(in, P, out, W.data(), out, g->data(), g->rows(), g_next->data(),
                                    g_next->rows(), blocking);
    g_next->topLeftCorner(in, P).array() *= (h.leftCols(P).array() > 0.0f).cast<float>();
    std::swap(g, g_next);
  }
  grad->setZero();
  GemmAccumulate<Eigen::RowMajor>(du, P, w0, W0.data() + ctx * w0, w0, g->data(), g->rows(),
                                  grad->data(), grad->rows(), blocking);
}

JointVector EnergyModel::Normalise(const JointVector& q) const {
  return (2.0 * (q - parts_.lower).array() / (parts_.upper - parts_.lower).array() - 1.0).matrix();
}

JointVector EnergyModel::Denormalise(const JointVector& u) const {
  return (parts_.lower.array() + (u.array() + 1.0) * 0.5 * (parts_.upper - parts_.lower).array())
      .matrix();
}

Eigen::VectorXd EnergyModel::CommandsToRadians(const Eigen::Ref<const Eigen::VectorXf>& u) const {
  FS_THROW_UNLESS(u.size() == command_size(), "EnergyModel::CommandsToRadians: ", u.size(),
                  " entries, expected ", command_size());
  Eigen::VectorXd y(u.size());
  for (int c = 0; c < parts_.intermediate_commands; ++c)
    y.segment<kDof>(kDof * c) = Denormalise(u.segment<kDof>(kDof * c).cast<double>());
  return y;
}

Eigen::VectorXf EnergyModel::RadiansToCommands(const Eigen::Ref<const Eigen::VectorXd>& y) const {
  FS_THROW_UNLESS(y.size() == command_size(), "EnergyModel::RadiansToCommands: ", y.size(),
                  " entries, expected ", command_size());
  Eigen::VectorXf u(y.size());
  for (int c = 0; c < parts_.intermediate_commands; ++c)
    u.segment<kDof>(kDof * c) = Normalise(y.segment<kDof>(kDof * c)).cast<float>();
  return u;
}

// ---------------------------------------------------------------------------------------------
double SgldStepVariance(const SgldParams& params, int k) {
  return params.step_scale / std::sqrt(1.0 + k);
}

namespace {

/// Columns per alignment unit of the threads' blocks: Eigen's GEMM kernels take the columns of
/// a product in groups (4 for float below AVX-512) and the leftover ones by another path, so a
/// column's rounding depends on its position in its block modulo the group. Blocks that start at
/// multiples of 8 give every column the position it has in one undivided product.
constexpr int kBlockAlign = 4;

/// E and dE/du (or E alone) of u's columns, split into contiguous blocks over the workspaces'
/// threads (the calling thread takes the first). Each block writes its own columns.
void EvaluateBlocks(const EnergyModel& model, const Eigen::VectorXf& context,
                    const Eigen::MatrixXf& u, int active, bool with_grad,
                    EnergyModel::Workspace* const* ws, int threads, Eigen::VectorXf* E,
                    Eigen::MatrixXf* G) {
  const int units = (active + kBlockAlign - 1) / kBlockAlign;
  if (threads <= 1 || units < 2) {
    model.EnergyAndGradient(context, u.leftCols(active), E, with_grad ? G : nullptr, ws[0]);
    return;
  }
  const int blocks = std::min(threads, units);
  if (E->size() != active) E->resize(active);
  if (with_grad && (G->rows() != u.rows() || G->cols() != active)) G->resize(u.rows(), active);
  std::vector<Eigen::VectorXf> e(static_cast<std::size_t>(blocks));
  std::vector<Eigen::MatrixXf> g(static_cast<std::size_t>(blocks));
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(blocks));
  const auto run = [&](int b) {
    const auto B = static_cast<std::size_t>(b);
    try {
      const int from = kBlockAlign * (units * b / blocks);
      const int to = std::min(active, kBlockAlign * (units * (b + 1) / blocks));
      model.EnergyAndGradient(context, u.middleCols(from, to - from), &e[B],
                              with_grad ? &g[B] : nullptr, ws[b]);
      E->segment(from, to - from) = e[B];
      if (with_grad) G->middleCols(from, to - from) = g[B];
    } catch (...) {
      errors[B] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(blocks - 1));
  for (int b = 1; b < blocks; ++b) pool.emplace_back(run, b);
  run(0);
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e_ptr : errors)
    if (e_ptr) std::rethrow_exception(e_ptr);
}

}  // namespace

int SgldBlockCapacity(int particles, int threads) {
  const int units = (particles + kBlockAlign - 1) / kBlockAlign;
  if (threads <= 1 || units < 2) return particles;
  return std::min(particles, kBlockAlign * ((units + threads - 1) / threads));
}

namespace {

SgldResult RunSgldOn(const EnergyModel& model, const Eigen::VectorXf& context,
                     const SgldParams& params, std::mt19937_64* rng,
                     EnergyModel::Workspace* const* ws, int threads, const Eigen::MatrixXf* start) {
  const int P = params.particles, D = model.command_size();
  FS_THROW_UNLESS(
      P >= 1 && params.steps >= 0 && std::isfinite(params.step_scale) && params.step_scale > 0 &&
          params.max_dropped_share >= 0 && params.max_dropped_share <= 1,
      "RunSgld: bad parameters (particles ", P, ", steps ", params.steps, ", step_scale ",
      params.step_scale, ", max_dropped_share ", params.max_dropped_share, ")");
  FS_THROW_UNLESS(threads >= 1, "RunSgld: no workspace given");
  const int per_thread = SgldBlockCapacity(P, threads);
  for (int t = 0; t < threads; ++t)
    FS_THROW_UNLESS(ws[t]->max_particles >= per_thread, "RunSgld: ", per_thread,
                    " particles per thread for a workspace made for ", ws[t]->max_particles);
  Eigen::MatrixXf u(D, P);
  if (start) {
    FS_THROW_UNLESS(start->rows() == D && start->cols() == P && start->allFinite() &&
                        start->cwiseAbs().maxCoeff() <= 1.0f,
                    "RunSgld: the start particles are ", start->rows(), " x ", start->cols(),
                    ", expected ", D, " x ", P, ", finite and in [-1, 1]");
    u = *start;
  } else {
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    for (Eigen::Index i = 0; i < u.size(); ++i) u.data()[i] = static_cast<float>(uniform(*rng));
  }
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXf E;
  Eigen::MatrixXf G;
  int active = P, dropped = 0;
  // Drops (keeping the order) the particles with a non-finite energy or gradient.
  const auto drop = [&](bool with_grad) {
    int kept = 0;
    for (int p = 0; p < active; ++p) {
      const bool ok = std::isfinite(E[p]) && (!with_grad || G.col(p).allFinite());
      if (!ok) continue;
      if (kept != p) {
        u.col(kept) = u.col(p);
        E[kept] = E[p];
        if (with_grad) G.col(kept) = G.col(p);
      }
      ++kept;
    }
    dropped += active - kept;
    active = kept;
    FS_THROW_UNLESS(dropped <= params.max_dropped_share * P, "RunSgld: ", dropped, " of ", P,
                    " particles became non-finite (share ", static_cast<double>(dropped) / P,
                    "), above max_dropped_share ", params.max_dropped_share);
  };
  for (int k = 0; k < params.steps && active > 0; ++k) {
    EvaluateBlocks(model, context, u, active, true, ws, threads, &E, &G);
    drop(true);
    const double s2 = SgldStepVariance(params, k);
    const double half = 0.5 * s2, noise = std::sqrt(s2);
    for (int p = 0; p < active; ++p)
      for (int d = 0; d < D; ++d) {
        const double next = u(d, p) - half * G(d, p) + noise * normal(*rng);
        u(d, p) = static_cast<float>(std::clamp(next, -1.0, 1.0));
      }
  }
  SgldResult result;
  if (active > 0) {
    EvaluateBlocks(model, context, u, active, false, ws, threads, &E, &G);
    drop(false);
  }
  std::vector<int> order(static_cast<std::size_t>(active));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return E[a] < E[b]; });
  result.u.resize(D, active);
  result.energy.resize(active);
  for (int i = 0; i < active; ++i) {
    result.u.col(i) = u.col(order[static_cast<std::size_t>(i)]);
    result.energy[i] = E[order[static_cast<std::size_t>(i)]];
  }
  result.dropped = dropped;
  return result;
}

}  // namespace

SgldResult RunSgld(const EnergyModel& model, const Eigen::VectorXf& context,
                   const SgldParams& params, std::mt19937_64* rng, EnergyModel::Workspace* ws,
                   const Eigen::MatrixXf* start) {
  return RunSgldOn(model, context, params, rng, &ws, 1, start);
}

SgldResult RunSgld(const EnergyModel& model, const Eigen::VectorXf& context,
                   const SgldParams& params, std::mt19937_64* rng,
                   std::vector<EnergyModel::Workspace>* workspaces, const Eigen::MatrixXf* start) {
  std::vector<EnergyModel::Workspace*> ws;
  for (EnergyModel::Workspace& w : *workspaces) ws.push_back(&w);
  return RunSgldOn(model, context, params, rng, ws.data(), static_cast<int>(ws.size()), start);
}

// ---------------------------------------------------------------------------------------------
LearnedSampler::LearnedSampler(const EnergyModel& model, SgldParams params)
    : ContextSampler(model), params_(params) {
  FS_THROW_UNLESS(params.threads >= 1, "LearnedSampler: threads must be >= 1, got ",
                  params.threads);
}

void ContextSampler::SetWorld(const World& world) { SetEncoding(model_.EncodeWorld(world)); }

void ContextSampler::SetEncoding(const Eigen::VectorXf& encoding) {
  FS_THROW_UNLESS(encoding.size() == model_.encoding_size(), "ContextSampler: an encoding of ",
                  encoding.size(), " entries, the model's encoder gives ", model_.encoding_size());
  encoding_ = encoding;
  has_world_ = true;
}

const Eigen::VectorXf& ContextSampler::PrepareContext(const char* who, const GfcsQuery& query,
                                                      int intermediate_commands, int count) {
  FS_THROW_UNLESS(intermediate_commands == model_.intermediate_commands(), who, ": asked for ",
                  intermediate_commands, " intermediate commands, the energy model works with ",
                  model_.intermediate_commands());
  FS_THROW_UNLESS(has_world_, who, ": call SetWorld before Sample");
  FS_THROW_UNLESS(count >= 0, who, ": count ", count, " is negative");
  model_.Context(query, encoding_, &context_);
  return context_;
}

void LearnedSampler::Sample(const GfcsQuery& query, int intermediate_commands, int count,
                            std::mt19937_64* rng, Eigen::MatrixXd* out) {
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::VectorXf& context =
      PrepareContext("LearnedSampler", query, intermediate_commands, count);
  FS_THROW_UNLESS(params_.uniform_share >= 0 && params_.uniform_share <= 1,
                  "LearnedSampler: uniform_share ", params_.uniform_share, " is outside [0, 1]");
  const int learned =
      count - static_cast<int>(std::lround(params_.uniform_share * static_cast<double>(count)));
  const int D = model_.command_size();
  out->resize(D, count);
  int kept = 0;
  last_ = SgldResult{};
  if (learned > 0) {
    SgldParams p = params_;
    p.particles = std::max(p.particles, learned);
    const int threads = std::max(1, p.threads);
    const int per_thread = SgldBlockCapacity(p.particles, threads);
    if (static_cast<int>(ws_.size()) != threads || ws_.front().max_particles < per_thread) {
      ws_.clear();
      for (int t = 0; t < threads; ++t) ws_.push_back(model_.MakeWorkspace(per_thread));
    }
    const Eigen::MatrixXf* start = nullptr;
    if (start_) {  // particles start at another sampler's candidates instead of uniform draws
      start_->Sample(query, intermediate_commands, p.particles, rng, &start_radians_);
      start_u_.resize(model_.command_size(), p.particles);
      for (int c = 0; c < p.particles; ++c)
        start_u_.col(c) =
            model_.RadiansToCommands(start_radians_.col(c)).cwiseMax(-1.0f).cwiseMin(1.0f);
      start = &start_u_;
    }
    last_ = RunSgld(model_, context, p, rng, &ws_, start);
    const int survivors = static_cast<int>(last_.u.cols());
    kept = std::min<int>(learned, survivors);
    picked_.resize(static_cast<std::size_t>(survivors));
    std::iota(picked_.begin(), picked_.end(), 0);
    if (p.pick == SgldPick::kRandom && kept < survivors) {
      // A partial Fisher-Yates shuffle: the first `kept` entries are a uniform draw without
      // replacement; kept in energy order so that the batch's order means the same either way.
      for (int c = 0; c < kept; ++c) {
        std::uniform_int_distribution<int> pick(c, survivors - 1);
        std::swap(picked_[static_cast<std::size_t>(c)],
                  picked_[static_cast<std::size_t>(pick(*rng))]);
      }
      std::sort(picked_.begin(), picked_.begin() + kept);
    }
    for (int c = 0; c < kept; ++c)
      out->col(c) = model_.CommandsToRadians(last_.u.col(picked_[static_cast<std::size_t>(c)]));
  }
  last_filled_ = learned - kept;
  FillUniform(model_.parts().lower, model_.parts().upper, kept, rng, out);
  last_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace foresight::manipulation
