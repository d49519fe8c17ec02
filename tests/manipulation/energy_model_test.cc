// The learned sampler's energy engine (torch-free): energies and gradients against an independent
// double-precision reference with central differences, artifacts, shape errors, no allocation on
// the hot path, SGLD (schedule, clamping, descent, determinism, non-finite particles) and the
// LearnedSampler; the solution memory and the nearest-neighbour sampler.

#include "inference/manipulation/energy_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <random>

#include "core/h5.h"
#include "inference/engine/artifact.h"
#include "inference/manipulation/nearest_sampler.h"
// Eigen's GEMM takes its packing buffers from malloc (not operator new) when no buffer is given:
// count malloc too (not under AddressSanitizer, which owns malloc).
#define FORESIGHT_ALLOC_COUNTER_MALLOC 1
#include "tests/alloc_counter.h"
#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

using testing::ExpectErrorContains;
using testing::TempDir;

Mlp RandomMlp(const std::vector<int>& sizes, std::mt19937_64* rng) {
  std::vector<DenseLayer> layers;
  std::normal_distribution<float> n01;
  for (std::size_t i = 0; i + 1 < sizes.size(); ++i) {
    DenseLayer l;
    const float scale = 1.5f / std::sqrt(static_cast<float>(sizes[i]));
    l.weight =
        Eigen::MatrixXf::NullaryExpr(sizes[i + 1], sizes[i], [&] { return scale * n01(*rng); });
    l.bias = Eigen::VectorXf::NullaryExpr(sizes[i + 1], [&] { return 0.3f * n01(*rng); });
    layers.push_back(std::move(l));
  }
  return Mlp(std::move(layers));
}

/// A small model: lattice of 8 points, encoding 5, n intermediate commands, energy hidden sizes.
EnergyModelParts RandomParts(int n, const std::vector<int>& hidden, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  EnergyModelParts p;
  p.lattice.lower = Eigen::Vector3d(0, 0, 0);
  p.lattice.upper = Eigen::Vector3d(0.3, 0.3, 0.3);
  p.lattice.spacing = 0.3;
  p.lattice.max_distance = 1.0;
  p.bps_mean = Eigen::VectorXf::Constant(8, 0.4f);
  p.bps_std = Eigen::VectorXf::Constant(8, 0.2f);
  p.encoder = RandomMlp({8, 6, 5}, &rng);
  std::vector<int> sizes = {21 + 5 + 7 * n};
  sizes.insert(sizes.end(), hidden.begin(), hidden.end());
  sizes.push_back(1);
  p.energy = RandomMlp(sizes, &rng);
  p.lower << -2.9, -1.76, -2.9, -3.07, -2.9, -0.02, -2.9;
  p.upper << 2.9, 1.76, 2.9, -0.07, 2.9, 3.75, 2.9;
  p.velocity_scale = 2.0;
  p.intermediate_commands = n;
  return p;
}

/// Independent reference: E([x_c; u]) in double by plain loops.
double ReferenceEnergy(const EnergyModelParts& p, const Eigen::VectorXd& context,
                       const Eigen::VectorXd& u) {
  Eigen::VectorXd x(context.size() + u.size());
  x << context, u;
  const auto& layers = p.energy.layers();
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Eigen::MatrixXd W = layers[i].weight.cast<double>();
    Eigen::VectorXd y(W.rows());
    for (int r = 0; r < W.rows(); ++r) {
      double s = layers[i].bias[r];
      for (int c = 0; c < W.cols(); ++c) s += W(r, c) * x[c];
      y[r] = (i + 1 < layers.size()) ? std::max(0.0, s) : s;
    }
    x = y;
  }
  return x[0];
}

Eigen::MatrixXf RandomU(int rows, int cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  return Eigen::MatrixXf::NullaryExpr(rows, cols, [&] { return u(rng); });
}

GfcsQuery SomeQuery() {
  GfcsQuery q;
  q.start << 0.1, -0.5, 0.2, -2.0, 0.3, 1.5, 0.7;
  q.start_velocity << 0.2, -0.4, 0.0, 1.0, 0.0, 0.0, -2.0;
  q.goal << -1.0, 0.5, 0.4, -1.2, -0.3, 2.0, -0.5;
  return q;
}

World SomeWorld() {
  World w;
  Box b;
  b.X_WB.translation() = Eigen::Vector3d(0.2, 0.1, 0.15);
  b.half_size = Eigen::Vector3d(0.05, 0.1, 0.2);
  w.AddBox("b", b);
  return w;
}

TEST(EnergyModel, SizesContextAndNormalisation) {
  const EnergyModel m(RandomParts(2, {16, 16, 16}, 1));
  EXPECT_EQ(m.encoding_size(), 5);
  EXPECT_EQ(m.context_size(), 26);
  EXPECT_EQ(m.command_size(), 14);
  const GfcsQuery q = SomeQuery();
  const Eigen::VectorXf enc = m.EncodeWorld(SomeWorld());
  ASSERT_EQ(enc.size(), 5);
  // the encoding is encoder((bps - mean) / std)
  {
    const Eigen::VectorXf x = (EncodeBps(SomeWorld(), m.parts().lattice).array() - 0.4f) / 0.2f;
    Mlp::Workspace ws = m.parts().encoder.MakeWorkspace();
    EXPECT_TRUE(m.parts().encoder.Forward(x, &ws).isApprox(enc));
  }
  Eigen::VectorXf ctx;
  m.Context(q, enc, &ctx);
  ASSERT_EQ(ctx.size(), 26);
  const JointVector lo = m.parts().lower, hi = m.parts().upper;
  for (int j = 0; j < kDof; ++j) {
    EXPECT_NEAR(ctx[j], 2 * (q.start[j] - lo[j]) / (hi[j] - lo[j]) - 1, 1e-6);
    EXPECT_NEAR(ctx[7 + j], q.start_velocity[j] / 2.0, 1e-6);
    EXPECT_NEAR(ctx[14 + j], 2 * (q.goal[j] - lo[j]) / (hi[j] - lo[j]) - 1, 1e-6);
  }
  EXPECT_EQ(ctx.tail(5), enc);
  EXPECT_TRUE(m.Normalise(lo).isApprox(-JointVector::Ones()));
  EXPECT_TRUE(m.Normalise(hi).isApprox(JointVector::Ones()));
  Eigen::VectorXd y(14);
  y << q.start, q.goal;
  EXPECT_TRUE(m.CommandsToRadians(m.RadiansToCommands(y)).isApprox(y, 1e-6));
  EXPECT_TRUE(m.Denormalise(m.Normalise(q.goal)).isApprox(q.goal));
}

TEST(EnergyModel, EnergyAndGradientMatchDoubleReferenceAndCentralDifferences) {
  for (const auto& hidden : std::vector<std::vector<int>>{{}, {7}, {16, 16, 16}, {64, 48, 32}}) {
    for (int n : {1, 3}) {
      const EnergyModelParts parts = RandomParts(n, hidden, 10 + n);
      const EnergyModel m(parts);
      Eigen::VectorXf ctx;
      m.Context(SomeQuery(), m.EncodeWorld(SomeWorld()), &ctx);
      const int P = 9;
      // u as a block of a wider matrix (outer stride != rows)
      const Eigen::MatrixXf wide = RandomU(m.command_size() + 3, P + 2, 7);
      const auto u = wide.block(1, 1, m.command_size(), P);
      auto ws = m.MakeWorkspace(P + 5);
      Eigen::VectorXf E;
      Eigen::MatrixXf G;
      m.EnergyAndGradient(ctx, u, &E, &G, &ws);
      ASSERT_EQ(E.size(), P);
      ASSERT_EQ(G.rows(), m.command_size());
      ASSERT_EQ(G.cols(), P);
      const Eigen::VectorXd c = ctx.cast<double>();
      for (int p = 0; p < P; ++p) {
        const Eigen::VectorXd up = u.col(p).cast<double>();
        const auto f = [&](const Eigen::VectorXd& x) { return ReferenceEnergy(parts, c, x); };
        const double e = f(up);
        EXPECT_NEAR(E[p], e, 1e-5 * (1 + std::abs(e))) << "hidden " << hidden.size() << " n " << n;
        const Eigen::VectorXd fd = testing::CentralGradient(f, up, 1e-6);
        const double scale = 1 + fd.cwiseAbs().maxCoeff();
        EXPECT_TRUE(testing::MatricesNear(G.col(p).cast<double>(), fd, 1e-4 * scale))
            << "hidden " << hidden.size() << " n " << n << " particle " << p;
      }
      // energies without the gradient are the same numbers
      Eigen::VectorXf E2;
      m.EnergyAndGradient(ctx, u, &E2, nullptr, &ws);
      EXPECT_EQ(E2, E);
      // fewer particles: the same columns
      m.EnergyAndGradient(ctx, u.leftCols(3), &E2, &G, &ws);
      EXPECT_TRUE(E2.isApprox(E.head(3), 1e-6f));  // GEMM panels may round differently
    }
  }
}

TEST(EnergyModel, NoAllocationOnTheHotPath) {
  const EnergyModel m(RandomParts(2, {800, 800, 800}, 3));
  Eigen::VectorXf ctx;
  m.Context(SomeQuery(), m.EncodeWorld(SomeWorld()), &ctx);
  auto ws = m.MakeWorkspace(200);
  const Eigen::MatrixXf u = RandomU(m.command_size(), 200, 4);
#ifdef FORESIGHT_COUNTS_MALLOC
  {  // the malloc counter is live: Eigen's own product mallocs its packing buffers
    const Eigen::MatrixXf a = Eigen::MatrixXf::Ones(800, 800), b = Eigen::MatrixXf::Ones(800, 200);
    Eigen::MatrixXf c(800, 200);
    g_allocations = 0;
    g_counting = true;
    c.noalias() = a * b;
    g_counting = false;
    EXPECT_GT(g_allocations.load(), 0);
  }
#endif
  for (int P : {200, 20, 1}) {
    Eigen::VectorXf E(P);
    Eigen::MatrixXf G(m.command_size(), P);
    g_allocations = 0;  // operator new and (where counted) malloc
    g_counting = true;
    m.EnergyAndGradient(ctx, u.leftCols(P), &E, &G, &ws);
    m.EnergyAndGradient(ctx, u.leftCols(P), &E, nullptr, &ws);
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << P << " particles";
    EXPECT_TRUE(E.allFinite() && G.allFinite());
  }
}

TEST(EnergyModel, SaveLoadRoundTrip) {
  TempDir tmp;
  const EnergyModelParts parts = RandomParts(2, {16, 12}, 5);
  const EnergyModel m(parts);
  const std::string path = tmp.File("energy.h5");
  m.Save(path, "model: gfcs_energy\n", 42);
  const EnergyModel back = EnergyModel::Load(path);
  const EnergyModelParts& q = back.parts();
  EXPECT_EQ(q.lattice.lower, parts.lattice.lower);
  EXPECT_EQ(q.lattice.upper, parts.lattice.upper);
  EXPECT_EQ(q.lattice.spacing, parts.lattice.spacing);
  EXPECT_EQ(q.lattice.max_distance, parts.lattice.max_distance);
  EXPECT_EQ(q.bps_mean, parts.bps_mean);
  EXPECT_EQ(q.bps_std, parts.bps_std);
  EXPECT_EQ(q.lower, parts.lower);
  EXPECT_EQ(q.upper, parts.upper);
  EXPECT_EQ(q.velocity_scale, parts.velocity_scale);
  EXPECT_EQ(q.intermediate_commands, 2);
  ASSERT_EQ(q.energy.layers().size(), 3u);
  ASSERT_EQ(q.encoder.layers().size(), 2u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(q.energy.layers()[i].weight, parts.energy.layers()[i].weight);
    EXPECT_EQ(q.energy.layers()[i].bias, parts.energy.layers()[i].bias);
  }
  EXPECT_EQ(back.EncodeWorld(SomeWorld()), m.EncodeWorld(SomeWorld()));
  const Artifact art = Artifact::Open(path, kEnergyModelType);
  EXPECT_EQ(art.seed(), 42);
  EXPECT_EQ(art.config_yaml(), "model: gfcs_energy\n");
  EXPECT_TRUE(art.file().Exists("/weights/energy/linear0/weight"));
  EXPECT_TRUE(art.file().Exists("/weights/encoder/linear1/bias"));
}

TEST(EnergyModel, CorruptOrMissingArtifactsAreErrorsNamingFileAndObject) {
  TempDir tmp;
  const EnergyModel m(RandomParts(1, {8}, 6));
  const std::string good = tmp.File("good.h5");
  m.Save(good, "", 1);
  ExpectErrorContains([&] { EnergyModel::Load(tmp.File("none.h5")); }, {"none.h5"});
  {
    const std::string path = tmp.File("other.h5");
    h5::WriteAtomically(path,
                        [](h5::File* f) { Artifact::WriteHeader(f, "span_predictor", "", 0); });
    ExpectErrorContains([&] { EnergyModel::Load(path); }, {"other.h5", "span_predictor"});
  }
  {
    const std::string path = tmp.File("short.h5");
    std::filesystem::copy_file(good, path);
    testing::Truncate(path, 1000);
    ExpectErrorContains([&] { EnergyModel::Load(path); }, {"short.h5"});
  }
  {
    const std::string path = tmp.File("layers.h5");
    std::filesystem::copy_file(good, path);
    testing::OverwriteAttr(path, "/model", "energy_layers", std::int64_t{3});
    ExpectErrorContains([&] { EnergyModel::Load(path); }, {"layers.h5", "/weights/energy/linear2"});
  }
  {
    const std::string path = tmp.File("n.h5");
    std::filesystem::copy_file(good, path);
    testing::OverwriteAttr(path, "/model", "intermediate_commands", std::int64_t{2});
    ExpectErrorContains([&] { EnergyModel::Load(path); }, {"n.h5", "energy network takes", "33"});
  }
  {
    const std::string path = tmp.File("scale.h5");
    std::filesystem::copy_file(good, path);
    testing::OverwriteAttr(path, "/model", "velocity_scale", -1.0);
    ExpectErrorContains([&] { EnergyModel::Load(path); }, {"scale.h5", "velocity_scale"});
  }
  {
    const std::string path = tmp.File("missing.h5");
    h5::WriteAtomically(path, [](h5::File* f) {
      Artifact::WriteHeader(f, kEnergyModelType, "", 0);
      f->SetAttr("/model", "intermediate_commands", std::int64_t{1});
      f->SetAttr("/model", "velocity_scale", 1.0);
      f->SetAttr("/model", "bps_spacing", 0.3);
      f->SetAttr("/model", "bps_max_distance", 1.0);
    });
    ExpectErrorContains([&] { EnergyModel::Load(path); }, {"missing.h5", "/model/bps_lower"});
  }
}

TEST(EnergyModel, ShapeErrorsNameTheMismatch) {
  {
    auto p = RandomParts(1, {8}, 7);
    p.bps_mean.resize(7);
    ExpectErrorContains([&] { EnergyModel m(p); }, {"bps_mean", "7", "N_R = 8"});
  }
  {
    auto p = RandomParts(1, {8}, 7);
    p.bps_std[2] = 0;
    ExpectErrorContains([&] { EnergyModel m(p); }, {"bps_std"});
  }
  {
    auto p = RandomParts(1, {8}, 7);
    p.lattice.upper.x() = 0.6;  // 12 points
    p.bps_mean = Eigen::VectorXf::Zero(12);
    p.bps_std = Eigen::VectorXf::Ones(12);
    ExpectErrorContains([&] { EnergyModel m(p); }, {"encoder takes 8", "N_R = 12"});
  }
  {
    auto p = RandomParts(1, {8}, 7);
    p.intermediate_commands = 2;
    ExpectErrorContains([&] { EnergyModel m(p); }, {"takes 33 inputs", "= 40"});
  }
  {
    auto p = RandomParts(1, {8}, 7);
    std::mt19937_64 rng(1);
    p.energy = RandomMlp({33, 8, 2}, &rng);
    ExpectErrorContains([&] { EnergyModel m(p); }, {"gives 2 outputs"});
  }
  {
    auto p = RandomParts(1, {8}, 7);
    p.energy = Mlp();
    ExpectErrorContains([&] { EnergyModel m(p); }, {"no layers"});
  }
  {
    auto p = RandomParts(1, {8}, 7);
    std::swap(p.lower[3], p.upper[3]);
    ExpectErrorContains([&] { EnergyModel m(p); }, {"joint limits"});
  }
  const EnergyModel m(RandomParts(1, {8}, 7));
  auto ws = m.MakeWorkspace(4);
  Eigen::VectorXf E;
  Eigen::MatrixXf G;
  const Eigen::VectorXf ctx = Eigen::VectorXf::Zero(26);
  ExpectErrorContains(
      [&] { m.EnergyAndGradient(Eigen::VectorXf::Zero(25), RandomU(7, 2, 1), &E, &G, &ws); },
      {"context has 25", "26"});
  ExpectErrorContains([&] { m.EnergyAndGradient(ctx, RandomU(14, 2, 1), &E, &G, &ws); },
                      {"u has 14 rows", "7"});
  ExpectErrorContains([&] { m.EnergyAndGradient(ctx, RandomU(7, 5, 1), &E, &G, &ws); },
                      {"5 particles", "4"});
  ExpectErrorContains([&] { m.Context(SomeQuery(), Eigen::VectorXf::Zero(4), &E); },
                      {"encoding has 4", "5"});
}

// ---------------------------------------------------------------------------------------------
/// E(u) = weight * sum_i |u_i - target| (+ 0 context): 2-layer ReLU net, minimum at u = target.
EnergyModelParts AbsEnergy(int n, float target, float weight) {
  EnergyModelParts p = RandomParts(n, {}, 1);
  const int D = 7 * n, ctx = 26;
  DenseLayer h, o;
  h.weight = Eigen::MatrixXf::Zero(2 * D, ctx + D);
  h.bias.resize(2 * D);
  for (int i = 0; i < D; ++i) {
    h.weight(i, ctx + i) = 1;
    h.bias[i] = -target;
    h.weight(D + i, ctx + i) = -1;
    h.bias[D + i] = target;
  }
  o.weight = Eigen::MatrixXf::Constant(1, 2 * D, weight);
  o.bias = Eigen::VectorXf::Zero(1);
  p.energy = Mlp({h, o});
  return p;
}

/// E(u) = w . u + b: one linear layer, constant gradient w.
EnergyModelParts LinearEnergy(int n, const Eigen::VectorXf& w) {
  EnergyModelParts p = RandomParts(n, {}, 1);
  DenseLayer l;
  l.weight = Eigen::MatrixXf::Zero(1, 26 + 7 * n);
  l.weight.rightCols(7 * n) = w.transpose();
  l.bias = Eigen::VectorXf::Constant(1, 0.5f);
  p.energy = Mlp({l});
  return p;
}

TEST(Sgld, StepVarianceSchedule) {
  SgldParams p;
  p.step_scale = 0.02;
  EXPECT_DOUBLE_EQ(SgldStepVariance(p, 0), 0.02);
  EXPECT_DOUBLE_EQ(SgldStepVariance(p, 3), 0.01);
  EXPECT_DOUBLE_EQ(SgldStepVariance(p, 8), 0.02 / 3);
}

TEST(Sgld, UpdatesFollowTheScheduleWithClampingAndAreDeterministic) {
  // Constant gradient w: replay the documented update with the same random stream.
  const int n = 1, D = 7;
  Eigen::VectorXf w(D);
  w << 30, -30, 0.5, -0.5, 0, 100, -100;
  const EnergyModel m(LinearEnergy(n, w));
  SgldParams p;
  p.particles = 13;
  p.steps = 7;
  p.step_scale = 0.05;
  Eigen::VectorXf ctx = Eigen::VectorXf::Zero(26);
  auto ws = m.MakeWorkspace(p.particles);
  std::mt19937_64 rng(99);
  const SgldResult r = RunSgld(m, ctx, p, &rng, &ws);
  // replay
  std::mt19937_64 replay(99);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXf u(D, p.particles);
  for (int i = 0; i < u.size(); ++i) u.data()[i] = static_cast<float>(uniform(replay));
  for (int k = 0; k < p.steps; ++k) {
    const double s2 = p.step_scale / std::sqrt(1.0 + k);
    for (int j = 0; j < p.particles; ++j)
      for (int d = 0; d < D; ++d)
        u(d, j) = static_cast<float>(
            std::clamp(u(d, j) - s2 / 2 * w[d] + std::sqrt(s2) * normal(replay), -1.0, 1.0));
  }
  Eigen::VectorXf e = (w.transpose() * u).transpose().array() + 0.5f;
  ASSERT_EQ(r.u.cols(), p.particles);
  EXPECT_EQ(r.dropped, 0);
  // sorted by energy ascending; the same set of particles as the replay
  for (int j = 0; j + 1 < p.particles; ++j) EXPECT_LE(r.energy[j], r.energy[j + 1]);
  for (int j = 0; j < p.particles; ++j) {
    Eigen::Index best;
    (u.colwise() - r.u.col(j)).colwise().norm().minCoeff(&best);
    EXPECT_LT((u.col(best) - r.u.col(j)).norm(), 1e-5f);
    EXPECT_NEAR(r.energy[j], e[best], 1e-4);
  }
  // strong gradients pin the coordinates at the bounds (clamped)
  EXPECT_TRUE((r.u.row(5).array() == -1.0f).all());
  EXPECT_TRUE((r.u.row(6).array() == 1.0f).all());
  EXPECT_TRUE((r.u.array().abs() <= 1.0f).all());
  // deterministic for a given rng state; another state differs
  std::mt19937_64 again(99);
  const SgldResult r2 = RunSgld(m, ctx, p, &again, &ws);
  EXPECT_EQ(r2.u, r.u);
  EXPECT_EQ(r2.energy, r.energy);
  std::mt19937_64 other(100);
  EXPECT_NE(RunSgld(m, ctx, p, &other, &ws).u, r.u);
}

TEST(Sgld, DescendsTheEnergyToItsMinimum) {
  const float target = 0.3f;
  const EnergyModel m(AbsEnergy(2, target, 100.0f));
  SgldParams p;  // defaults: 200 particles, 50 steps, step_scale 0.01
  Eigen::VectorXf ctx = Eigen::VectorXf::Zero(26);
  auto ws = m.MakeWorkspace(p.particles);
  std::mt19937_64 rng(3);
  // initial energies of uniform particles: mean |u - 0.3| = 0.545 per coordinate
  const SgldResult r = RunSgld(m, ctx, p, &rng, &ws);
  ASSERT_EQ(r.u.cols(), 200);
  const double mean_abs = (r.u.array() - target).abs().mean();
  EXPECT_LT(mean_abs, 0.1) << "particles did not move to the minimum";
  EXPECT_LT(r.energy.mean(), 100.0 * 14 * 0.1);
  for (int j = 0; j + 1 < r.u.cols(); ++j) EXPECT_LE(r.energy[j], r.energy[j + 1]);
  // without steps, the particles stay uniform
  SgldParams none = p;
  none.steps = 0;
  const SgldResult r0 = RunSgld(m, ctx, none, &rng, &ws);
  EXPECT_GT((r0.u.array() - target).abs().mean(), 0.4);
  EXPECT_GT(r0.energy.mean(), 5 * r.energy.mean());
}

TEST(Sgld, NonFiniteParticlesAreDroppedAndCountedOrAnError) {
  // E = 1e30 relu(1e30 u_0): +inf energy and gradient for u_0 > 0, finite (0) otherwise.
  EnergyModelParts parts = RandomParts(1, {}, 1);
  DenseLayer h, o;
  h.weight = Eigen::MatrixXf::Zero(1, 33);
  h.weight(0, 26) = 1e30f;
  h.bias = Eigen::VectorXf::Zero(1);
  o.weight = Eigen::MatrixXf::Constant(1, 1, 1e30f);
  o.bias = Eigen::VectorXf::Zero(1);
  parts.energy = Mlp({h, o});
  const EnergyModel m(parts);
  Eigen::VectorXf ctx = Eigen::VectorXf::Zero(26);
  SgldParams p;
  p.particles = 100;
  p.steps = 5;
  p.max_dropped_share = 1.0;
  auto ws = m.MakeWorkspace(p.particles);
  std::mt19937_64 rng(8);
  const SgldResult r = RunSgld(m, ctx, p, &rng, &ws);
  EXPECT_GT(r.dropped, 20);
  EXPECT_EQ(r.dropped + r.u.cols(), p.particles);
  EXPECT_TRUE(r.energy.allFinite());
  EXPECT_TRUE((r.u.row(0).array() <= 0.0f).all());
  p.max_dropped_share = 0.1;
  std::mt19937_64 rng2(8);
  ExpectErrorContains([&] { RunSgld(m, ctx, p, &rng2, &ws); },
                      {"of 100 particles became non-finite", "max_dropped_share 0.1"});
  p.particles = 101;
  ExpectErrorContains([&] { RunSgld(m, ctx, p, &rng2, &ws); }, {"101 particles", "100"});
}

TEST(Sgld, ThreadsGiveTheSameParticlesAsOne) {
  // Widths around Eigen's cache blocking (256 as shipped, 800 as the thesis): a particle's
  // energy and gradient must not depend on which block of particles it is evaluated in.
  for (const int width : {64, 256, 800}) {
    const EnergyModel m(RandomParts(2, {width, width, width}, 7));
    Eigen::VectorXf ctx;
    m.Context(SomeQuery(), Eigen::VectorXf::Constant(m.encoding_size(), 0.1f), &ctx);
    SgldParams p;
    p.particles = 41;
    p.steps = 5;
    auto one = m.MakeWorkspace(p.particles);
    std::mt19937_64 rng(3);
    const SgldResult a = RunSgld(m, ctx, p, &rng, &one);
    for (const int threads : {2, 3}) {
      std::vector<EnergyModel::Workspace> many;
      for (int t = 0; t < threads; ++t)
        many.push_back(m.MakeWorkspace(SgldBlockCapacity(p.particles, threads)));
      std::mt19937_64 again(3);
      const SgldResult b = RunSgld(m, ctx, p, &again, &many);
      EXPECT_EQ(b.u, a.u) << "width " << width << ", " << threads << " threads";
      EXPECT_EQ(b.energy, a.energy) << "width " << width << ", " << threads << " threads";
    }
    // A workspace too small for its share is an error naming both sizes.
    ASSERT_EQ(SgldBlockCapacity(p.particles, 2), 24);  // blocks of 24 and 17
    std::vector<EnergyModel::Workspace> small;
    small.push_back(m.MakeWorkspace(20));
    small.push_back(m.MakeWorkspace(20));
    std::mt19937_64 rng2(3);
    ExpectErrorContains([&] { RunSgld(m, ctx, p, &rng2, &small); },
                        {"24 particles per thread", "made for 20"});
  }
}

TEST(Sgld, ParamsSerialize) {
  SgldParams p;
  p.particles = 20;
  const SgldParams back =
      config::FromYaml<SgldParams>(config::ParseYaml(config::ToYaml(p), "t"), "t");
  EXPECT_EQ(back.particles, 20);
  EXPECT_EQ(back.steps, 50);
  ExpectErrorContains(
      [] {
        config::FromYaml<SgldParams>(config::ParseYaml("max_dropped_share: 2", "s.yaml"), "s.yaml");
      },
      {"s.yaml", "max_dropped_share"});
}

TEST(LearnedSampler, ReturnsTheLowestEnergyParticlesInRadians) {
  const float target = -0.5f;
  const EnergyModel m(AbsEnergy(2, target, 100.0f));
  SgldParams p;
  p.particles = 50;
  p.steps = 30;
  LearnedSampler s(m, p);
  EXPECT_EQ(s.name(), "learned");
  CommandSampler* base = &s;
  std::mt19937_64 rng(4);
  Eigen::MatrixXd out;
  ExpectErrorContains([&] { base->Sample(SomeQuery(), 2, 5, &rng, &out); }, {"SetWorld"});
  s.SetWorld(SomeWorld());
  ExpectErrorContains([&] { base->Sample(SomeQuery(), 1, 5, &rng, &out); },
                      {"1 intermediate commands", "the energy model works with 2"});
  base->Sample(SomeQuery(), 2, 5, &rng, &out);
  ASSERT_EQ(out.rows(), 14);
  ASSERT_EQ(out.cols(), 5);
  EXPECT_EQ(s.last_result().u.cols(), 50);
  EXPECT_EQ(s.last_dropped(), 0);
  EXPECT_EQ(s.last_filled(), 0);
  EXPECT_GT(s.last_seconds(), 0);
  for (int c = 0; c < 5; ++c) {
    EXPECT_TRUE(out.col(c).isApprox(m.CommandsToRadians(s.last_result().u.col(c))));
    // near Denormalise(target) per joint
    const JointVector expect = m.Denormalise(JointVector::Constant(target));
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < kDof; ++j)
        EXPECT_NEAR(out(7 * k + j, c), expect[j], 0.1 * (m.parts().upper - m.parts().lower)[j]);
  }
  // more candidates than particles: SGLD runs with `count` particles
  base->Sample(SomeQuery(), 2, 80, &rng, &out);
  EXPECT_EQ(out.cols(), 80);
  EXPECT_EQ(s.last_result().u.cols(), 80);
  // on two threads: the same batch from the same stream
  SgldParams two = p;
  two.threads = 2;
  LearnedSampler s2(m, two);
  s2.SetWorld(SomeWorld());
  std::mt19937_64 r1(9), r2(9);
  Eigen::MatrixXd out1, out2;
  s.Sample(SomeQuery(), 2, 20, &r1, &out1);
  s2.Sample(SomeQuery(), 2, 20, &r2, &out2);
  EXPECT_EQ(out1, out2);
}

// sgld_pick random: the batch is a draw without replacement from the survivors (in their energy
// order), so over many calls every survivor rank appears, where the lowest-energy pick always
// returns the first ranks; the draw follows the caller's stream.
TEST(LearnedSampler, RandomPickDrawsSurvivorsWithoutReplacement) {
  const EnergyModel m(AbsEnergy(2, -0.5f, 100.0f));
  SgldParams p;
  p.particles = 40;
  p.steps = 5;
  p.pick = SgldPick::kRandom;
  LearnedSampler s(m, p);
  s.SetWorld(SomeWorld());
  std::vector<int> seen(40, 0);
  for (int call = 0; call < 30; ++call) {
    std::mt19937_64 rng(100 + call);
    Eigen::MatrixXd out;
    s.Sample(SomeQuery(), 2, 8, &rng, &out);
    ASSERT_EQ(out.cols(), 8);
    const Eigen::MatrixXf& u = s.last_result().u;
    int previous = -1;
    for (int c = 0; c < 8; ++c) {
      int rank = -1;  // the survivor this column came from
      for (int k = 0; k < u.cols() && rank < 0; ++k)
        if (out.col(c).isApprox(m.CommandsToRadians(u.col(k)), 1e-12)) rank = k;
      ASSERT_GE(rank, 0) << "column " << c << " is not a survivor";
      EXPECT_GT(rank, previous) << "distinct, in energy order";
      previous = rank;
      ++seen[static_cast<std::size_t>(rank)];
    }
  }
  int ranks_seen = 0, beyond_eighth = 0;
  for (int k = 0; k < 40; ++k) {
    ranks_seen += seen[static_cast<std::size_t>(k)] > 0;
    if (k >= 8) beyond_eighth += seen[static_cast<std::size_t>(k)];
  }
  EXPECT_GT(ranks_seen, 30);      // 240 draws of 8 from 40 reach nearly every rank
  EXPECT_GT(beyond_eighth, 150);  // the lowest-energy pick would have none (expected 192)
  // The same stream gives the same batch.
  std::mt19937_64 a(7), b(7);
  Eigen::MatrixXd out_a, out_b;
  s.Sample(SomeQuery(), 2, 8, &a, &out_a);
  s.Sample(SomeQuery(), 2, 8, &b, &out_b);
  EXPECT_EQ(out_a, out_b);
}

TEST(LearnedSampler, UniformShareDrawsThatPartOfTheBatchUniformlyInTheLimits) {
  const float target = -0.5f;
  const EnergyModel m(AbsEnergy(2, target, 100.0f));
  SgldParams p;
  p.particles = 50;
  p.steps = 30;
  p.uniform_share = 0.25;
  LearnedSampler s(m, p);
  s.SetWorld(SomeWorld());
  std::mt19937_64 rng(4);
  Eigen::MatrixXd out;
  s.Sample(SomeQuery(), 2, 20, &rng, &out);
  ASSERT_EQ(out.rows(), 14);
  ASSERT_EQ(out.cols(), 20);
  EXPECT_EQ(s.last_filled(), 0);  // the configured uniform part is not a shortfall
  const JointVector lo = m.parts().lower, hi = m.parts().upper;
  const JointVector expect = m.Denormalise(JointVector::Constant(target));
  EXPECT_EQ(s.last_result().u.cols(), 50);  // SGLD ran its configured particles
  // The first 15 are the lowest-energy SGLD particles, near the energy's minimum.
  double learned_spread = 0;
  for (int c = 0; c < 15; ++c) {
    EXPECT_TRUE(out.col(c).isApprox(m.CommandsToRadians(s.last_result().u.col(c)))) << c;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < kDof; ++j)
        learned_spread += std::abs(out(7 * k + j, c) - expect[j]) / (hi[j] - lo[j]) / 210.0;
  }
  EXPECT_LT(learned_spread, 0.05);
  // The last 5 are uniform in the limits: inside them, and spread where SGLD's are not.
  double spread = 0;
  for (int c = 15; c < 20; ++c)
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < kDof; ++j) {
        const double v = out(7 * k + j, c);
        EXPECT_GE(v, lo[j]);
        EXPECT_LE(v, hi[j]);
        spread += std::abs(v - expect[j]) / (hi[j] - lo[j]) / 70.0;
      }
  EXPECT_GT(spread, 0.15) << "uniform draws in [lo, hi] lie on average ~0.3 of the range away";
  // share 1: no SGLD at all; share 0 is the thesis (tested above)
  p.uniform_share = 1.0;
  LearnedSampler all_uniform(m, p);
  all_uniform.SetWorld(SomeWorld());
  all_uniform.Sample(SomeQuery(), 2, 20, &rng, &out);
  EXPECT_EQ(all_uniform.last_result().u.cols(), 0);
  EXPECT_EQ(all_uniform.last_filled(), 0);
  ASSERT_EQ(out.cols(), 20);
  for (int c = 0; c < 20; ++c)
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < kDof; ++j) {
        EXPECT_GE(out(7 * k + j, c), lo[j]);
        EXPECT_LE(out(7 * k + j, c), hi[j]);
      }
  // The uniform count is rounded to the nearest (half away from zero): 0.5 x 5 -> 3 uniform.
  p.uniform_share = 0.5;
  LearnedSampler half(m, p);
  half.SetWorld(SomeWorld());
  half.Sample(SomeQuery(), 2, 5, &rng, &out);
  ASSERT_EQ(out.cols(), 5);
  for (int c = 0; c < 2; ++c)
    EXPECT_TRUE(out.col(c).isApprox(m.CommandsToRadians(half.last_result().u.col(c)))) << c;
  for (int c = 2; c < 5; ++c)
    EXPECT_FALSE(out.col(c).isApprox(m.CommandsToRadians(half.last_result().u.col(c)))) << c;
  p.uniform_share = 1.5;
  LearnedSampler bad(m, p);
  bad.SetWorld(SomeWorld());
  ExpectErrorContains([&] { bad.Sample(SomeQuery(), 2, 20, &rng, &out); }, {"uniform_share 1.5"});
}

// --- The solution memory and the nearest-neighbour sampler --------------------------------------

/// Three memory problems: contexts of three queries in SomeWorld (start velocity zero, so those
/// seven dimensions do not vary), solutions 0-1 of problem 0, 2-4 of problem 2, 5 of problem 1,
/// costs not in solution order.
EnergyModelParts PartsWithMemory(std::vector<GfcsQuery>* queries) {
  EnergyModelParts p = RandomParts(1, {8}, 3);
  const EnergyModel plain(p);
  const Eigen::VectorXf enc = plain.EncodeWorld(SomeWorld());
  queries->clear();
  SolutionMemory& m = p.memory;
  m.contexts.resize(plain.context_size(), 3);
  for (int k = 0; k < 3; ++k) {
    GfcsQuery q = SomeQuery();
    q.start_velocity.setZero();
    q.start[0] += 0.4 * k;
    q.goal[3] -= 0.3 * k * k;
    Eigen::VectorXf ctx;
    plain.Context(q, enc, &ctx);
    m.contexts.col(k) = ctx;
    queries->push_back(q);
  }
  m.problem.resize(6);
  m.problem << 0, 0, 2, 2, 2, 1;
  m.cost.resize(6);
  m.cost << 3.0f, 1.0f, 2.5f, 0.5f, 1.5f, 4.0f;
  m.commands = RandomU(7, 6, 77);
  return p;
}

TEST(SolutionMemory, RoundTripsThroughTheArtifactAndBadMemoriesAreErrors) {
  std::vector<GfcsQuery> queries;
  const EnergyModelParts parts = PartsWithMemory(&queries);
  TempDir tmp;
  const std::string path = tmp.File("energy.h5");
  EnergyModel(parts).Save(path, "model: gfcs_energy\n", 1);
  const EnergyModel loaded = EnergyModel::Load(path);
  const SolutionMemory& back = loaded.parts().memory;
  EXPECT_EQ(back.contexts, parts.memory.contexts);
  EXPECT_EQ(back.problem, parts.memory.problem);
  EXPECT_EQ(back.cost, parts.memory.cost);
  EXPECT_EQ(back.commands, parts.memory.commands);
  // No memory: no /memory group, and an empty memory back.
  const std::string plain = tmp.File("plain.h5");
  EnergyModel(RandomParts(1, {8}, 3)).Save(plain, "model: gfcs_energy\n", 1);
  EXPECT_FALSE(Artifact::Open(plain, kEnergyModelType).file().Exists("/memory"));
  EXPECT_TRUE(EnergyModel::Load(plain).parts().memory.empty());

  EnergyModelParts bad = parts;
  bad.memory.problem[3] = 3;
  ExpectErrorContains([&] { EnergyModel m(bad); }, {"names problem 3", "outside its 3 contexts"});
  bad = parts;
  bad.memory.commands(2, 1) = 1.5f;
  ExpectErrorContains([&] { EnergyModel m(bad); }, {"memory's commands", "[-1, 1]"});
  bad = parts;
  bad.memory.contexts.conservativeResize(bad.memory.contexts.rows() - 1, Eigen::NoChange);
  ExpectErrorContains([&] { EnergyModel m(bad); }, {"contexts are 25 x 3", "expected 26 rows"});
  bad = parts;
  bad.memory.cost.conservativeResize(5);
  ExpectErrorContains([&] { EnergyModel m(bad); }, {"6 solutions", "5 costs"});
  const EnergyModel none(RandomParts(1, {8}, 3));
  ExpectErrorContains([&] { NearestSampler s(none, 4); }, {"no solution memory"});
}

TEST(NearestSampler, DistancesStandardiseEachDimensionAndWeighTheTwoBlocksEqually) {
  std::vector<GfcsQuery> queries;
  const EnergyModel model(PartsWithMemory(&queries));
  const NearestSampler sampler(model, 4);
  const Eigen::MatrixXd C = model.parts().memory.contexts.cast<double>();
  const Eigen::VectorXf x = RandomU(26, 1, 5).col(0);
  // Reference: population standard deviation per dimension over the 3 problems; dimensions with
  // none left out; the mean of z^2 over the varying state dimensions (0-20) plus that over the
  // varying encoding dimensions (21-25).
  double expected[3] = {0, 0, 0};
  for (int block = 0; block < 2; ++block) {
    const int from = block ? 21 : 0, to = block ? 26 : 21;
    int varying = 0;
    double sum[3] = {0, 0, 0};
    for (int i = from; i < to; ++i) {
      const double mean = (C(i, 0) + C(i, 1) + C(i, 2)) / 3;
      double var = 0;
      for (int p = 0; p < 3; ++p) var += (C(i, p) - mean) * (C(i, p) - mean) / 3;
      if (std::sqrt(var) <= 1e-6) continue;
      ++varying;
      for (int p = 0; p < 3; ++p) sum[p] += std::pow((x[i] - C(i, p)) / std::sqrt(var), 2);
    }
    // The start velocity (7) and the joints that no query moves do not vary; the encoding (one
    // world) does not either.
    EXPECT_EQ(varying, block ? 0 : 2) << "block " << block;
    for (int p = 0; p < 3; ++p) expected[p] += varying ? sum[p] / varying : 0;
  }
  const Eigen::VectorXd d = sampler.Distances(x);
  for (int p = 0; p < 3; ++p) EXPECT_NEAR(d[p], expected[p], 1e-9 * (1 + expected[p])) << p;
  EXPECT_NEAR(sampler.Distances(model.parts().memory.contexts.col(1))[1], 0.0, 1e-12);
}

TEST(NearestSampler, TakesTheNearestProblemsCheapestSolutionsThenFillsUniformly) {
  std::vector<GfcsQuery> queries;
  const EnergyModel model(PartsWithMemory(&queries));
  const SolutionMemory& m = model.parts().memory;
  NearestSampler sampler(model, 2);
  std::mt19937_64 rng(1);
  Eigen::MatrixXd out;
  ExpectErrorContains([&] { sampler.Sample(queries[0], 1, 3, &rng, &out); }, {"SetWorld"});
  sampler.SetWorld(SomeWorld());
  ExpectErrorContains([&] { sampler.Sample(queries[0], 2, 3, &rng, &out); },
                      {"NearestSampler: asked for 2", "the energy model works with 1"});
  // Query = problem 2's: problem 2 (distance 0; its two cheapest of three: 3, 4), then problem 1
  // (nearer than 0 in both varying joints: 5), then problem 0 (1, 0), then uniform draws.
  sampler.Sample(queries[2], 1, 7, &rng, &out);
  ASSERT_EQ(out.rows(), 7);
  ASSERT_EQ(out.cols(), 7);
  const int expected[5] = {3, 4, 5, 1, 0};
  for (int c = 0; c < 5; ++c)
    EXPECT_TRUE(out.col(c).isApprox(model.CommandsToRadians(m.commands.col(expected[c])), 1e-12))
        << "column " << c;
  EXPECT_EQ(sampler.last_filled(), 2);
  EXPECT_EQ(sampler.last_problems(), 3);
  const JointVector& lo = model.parts().lower;
  const JointVector& hi = model.parts().upper;
  for (int c = 5; c < 7; ++c)
    EXPECT_TRUE(((out.col(c).array() >= lo.array()) && (out.col(c).array() <= hi.array())).all());
  // A batch the nearest problem fills alone; no draw from the generator.
  const std::mt19937_64 before = rng;
  sampler.Sample(queries[2], 1, 1, &rng, &out);
  EXPECT_TRUE(out.col(0).isApprox(model.CommandsToRadians(m.commands.col(3)), 1e-12));
  EXPECT_EQ(sampler.last_filled(), 0);
  EXPECT_TRUE(rng == before);
}

TEST(LearnedSampler, SgldCanStartAtAnotherSamplersCandidates) {
  std::vector<GfcsQuery> queries;
  const EnergyModel model(PartsWithMemory(&queries));
  NearestSampler nearest(model, 4);
  nearest.SetWorld(SomeWorld());
  SgldParams params;
  params.particles = 3;
  params.steps = 0;  // no Langevin step: the survivors are the start points, by energy
  LearnedSampler learned(model, params);
  learned.SetWorld(SomeWorld());
  learned.SetStart(&nearest);
  std::mt19937_64 rng(2);
  Eigen::MatrixXd out, expected;
  learned.Sample(queries[2], 1, 3, &rng, &out);
  std::mt19937_64 unused(2);
  nearest.Sample(queries[2], 1, 3, &unused, &expected);
  // The same three candidates, in the order of their energies.
  Eigen::VectorXf E;
  Eigen::MatrixXf u(7, 3);
  for (int c = 0; c < 3; ++c) u.col(c) = model.RadiansToCommands(expected.col(c));
  auto ws = model.MakeWorkspace(3);
  Eigen::VectorXf context;
  model.Context(queries[2], model.EncodeWorld(SomeWorld()), &context);
  model.EnergyAndGradient(context, u, &E, nullptr, &ws);
  std::vector<int> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return E[a] < E[b]; });
  for (int c = 0; c < 3; ++c) EXPECT_TRUE(out.col(c).isApprox(expected.col(order[c]), 1e-5)) << c;
  // With steps the particles move from there, deterministically for a seed.
  params.steps = 5;
  LearnedSampler moving(model, params);
  moving.SetWorld(SomeWorld());
  moving.SetStart(&nearest);
  std::mt19937_64 a(3), b(3);
  Eigen::MatrixXd first, second;
  moving.Sample(queries[2], 1, 3, &a, &first);
  moving.Sample(queries[2], 1, 3, &b, &second);
  EXPECT_EQ(first, second);
  EXPECT_FALSE(first.isApprox(out, 1e-9));
  // Start points of the wrong shape are an error.
  Eigen::MatrixXf bad = Eigen::MatrixXf::Zero(7, 2);
  auto ws3 = model.MakeWorkspace(3);
  ExpectErrorContains([&] { RunSgld(model, context, params, &a, &ws3, &bad); },
                      {"start particles are 7 x 2", "expected 7 x 3"});
}

}  // namespace
}  // namespace foresight::manipulation
