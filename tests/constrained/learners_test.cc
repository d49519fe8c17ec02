// The learners of constrained prediction (thesis ch 7): prior, KTM baseline and naive network.
// Tiny trainings on synthetic straight and curved walks; KTM features against a direct
// computation; engine vs LibTorch parity; resume after an interrupt equals an uninterrupted run.

#include "training/constrained/learners.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/ego_frame.h"
#include "core/h5.h"
#include "inference/engine/artifact.h"
#include "inference/prediction/naive_predictor.h"
#include "inference/prediction/span_predictor.h"
#include "models/constrained/naive_net.h"
#include "models/span/span_net.h"
#include "tests/test_util.h"
// Last: it replaces the global allocator of this binary (counting only while g_counting).
#define FORESIGHT_ALLOC_COUNTER_MALLOC
#include "tests/alloc_counter.h"
#include "training/span/pipeline.h"
#include "training/trainer.h"

namespace foresight::constrained {
namespace {

using Path = Eigen::Matrix<double, Eigen::Dynamic, 2>;

/// `n` windows of walks at 0.8-1.6 m/s with a constant turn rate in [-0.4, 0.4] rad/s (half of
/// them straight), random start and heading.
WindowSet SyntheticWindows(int n, int p, int f, double dt, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  WindowSet w;
  w.seconds_per_step = dt;
  w.observed = p;
  w.predicted = f;
  w.past.resize(n, 2 * p);
  w.future.resize(n, 2 * f);
  w.track.assign(static_cast<std::size_t>(n), 0);
  for (int k = 0; k < n; ++k) {
    const double speed = 0.8 + 0.8 * u01(rng);
    const double turn = (k % 2 == 0) ? 0.0 : -0.4 + 0.8 * u01(rng);
    double heading = 2 * M_PI * u01(rng);
    Eigen::Vector2d x(10 * u01(rng) - 5, 10 * u01(rng) - 5);
    for (int i = 0; i < p + f; ++i) {
      if (i < p)
        w.past.row(k).segment<2>(2 * i) = x.transpose();
      else
        w.future.row(k).segment<2>(2 * (i - p)) = x.transpose();
      x += speed * dt * Eigen::Vector2d(std::cos(heading), std::sin(heading));
      heading += turn * dt;
    }
    w.track[static_cast<std::size_t>(k)] = k;
  }
  return w;
}

LearnerSpec TinySpec() {
  LearnerSpec s;
  s.observed = 6;
  s.predicted = 8;
  s.seconds_per_step = 0.4;
  s.seed = 5;
  s.basis.num_centres = 5;
  s.network.hidden = {16, 16};
  s.network.components = 2;
  s.network.u_param = UParam::kDiagonal;
  s.train.epochs = 3;
  s.train.batch_size = 32;
  s.train.patience = 0;
  s.train.progress = ProgressStyle::kNone;
  return s;
}

struct Data {
  WindowSet train, val;
};
const Data& TinyData() {
  static const Data d{SyntheticWindows(240, 6, 8, 0.4, 1), SyntheticWindows(60, 6, 8, 0.4, 2)};
  return d;
}

/// val_loss column of metrics.csv (epoch, train_loss, val_loss, ...).
std::vector<double> ValLosses(const std::string& dir) {
  std::ifstream in(dir + "/metrics.csv");
  std::string line;
  std::getline(in, line);
  std::vector<double> out;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    for (int c = 0; c < 3 && std::getline(ss, cell, ','); ++c) {
    }
    out.push_back(std::stod(cell));
  }
  return out;
}

Path RandomPast(int p, std::mt19937_64* rng) {
  std::normal_distribution<double> n01;
  Path past(p, 2);
  Eigen::Vector2d x(n01(*rng), n01(*rng));
  const double h = 3 * n01(*rng);
  for (int i = 0; i < p; ++i) {
    past.row(i) = x.transpose();
    x += 0.5 * Eigen::Vector2d(std::cos(h), std::sin(h)) +
         0.1 * Eigen::Vector2d(n01(*rng), n01(*rng));
  }
  return past;
}

/// Normalised ego-frame past [1, 2p] as the engines compute it.
Eigen::VectorXd EgoPast(const Path& past) {
  const int p = static_cast<int>(past.rows());
  const EgoFrame frame = EgoFrame::FromPast(
      p, [&](int i) { return Eigen::Vector2d(past(i, 0), past(i, 1)); }, true);
  Eigen::VectorXd q(2 * p);
  for (int i = 0; i < p; ++i) q.segment<2>(2 * i) = frame.ToEgo(past.row(i).transpose());
  return q;
}

torch::Tensor Row(const Eigen::VectorXd& v) {
  auto t = torch::zeros({1, v.size()}, torch::kFloat32);
  for (Eigen::Index i = 0; i < v.size(); ++i) t[0][i] = static_cast<float>(v[i]);
  return t;
}

TEST(Learners, KtmFeaturesAndReferencesMatchDirectComputation) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd q(7, 6);
  for (Eigen::Index i = 0; i < q.size(); ++i) q.data()[i] = n01(rng);
  const double l = 0.7;
  const Eigen::MatrixXd refs = ChooseKtmReferences(q, 3, 11);
  const Eigen::MatrixXd feat = KtmFeatures(q, refs, l);
  ASSERT_EQ(feat.rows(), 7);
  ASSERT_EQ(feat.cols(), 3);
  for (int n = 0; n < 7; ++n)
    for (int k = 0; k < 3; ++k) {
      double d2 = 0;  // RMS over the 3 points
      for (int j = 0; j < 3; ++j)
        d2 += std::pow(q(n, 2 * j) - refs(k, 2 * j), 2) +
              std::pow(q(n, 2 * j + 1) - refs(k, 2 * j + 1), 2);
      d2 /= 3;
      EXPECT_NEAR(feat(n, k), std::exp(-d2 / (2 * l * l)), 1e-14);
    }
  // Farthest-point: each next reference maximises the distance to the nearest chosen one
  // (brute force over all rows).
  auto d2 = [&](int a, const Eigen::RowVectorXd& r) { return (q.row(a) - r).squaredNorm() / 3; };
  for (int k = 1; k < 3; ++k) {
    double best = -1, got = 0;
    for (int i = 0; i < 7; ++i) {
      double nearest = 1e300;
      for (int c = 0; c < k; ++c) nearest = std::min(nearest, d2(i, refs.row(c)));
      best = std::max(best, nearest);
      if ((q.row(i) - refs.row(k)).norm() == 0) got = nearest;
    }
    EXPECT_DOUBLE_EQ(got, best) << "reference " << k;
  }
  testing::ExpectErrorContains([&] { ChooseKtmReferences(q, 8, 0); }, {"ktm.references = 8", "7"});
}

TEST(Learners, PriorTrainsExportsAndLoads) {
  testing::TempDir dir;
  const LearnerSpec spec = TinySpec();
  const std::string art = dir.File("prior.h5");
  ASSERT_TRUE(TrainPrior(spec, TinyData().train, TinyData().val, dir.File("prior"), false, {}, art,
                         "model: test\n"));
  const span::Predictor engine = span::Predictor::Load(art);
  EXPECT_EQ(engine.layout().components, 2);
  EXPECT_EQ(engine.layout().u_param, UParam::kDiagonal);
  EXPECT_EQ(engine.ktm_references().size(), 0);
  EXPECT_EQ(Artifact::Open(art, span::kModelType).config_yaml(), "model: test\n");
  const std::vector<double> val = ValLosses(dir.File("prior"));
  ASSERT_EQ(val.size(), 3u);
  for (double v : val) EXPECT_TRUE(std::isfinite(v));
  EXPECT_LT(val.back(), val.front()) << "the validation NLL does not improve on the first epoch";

  LearnerSpec chol = spec;
  chol.network.u_param = UParam::kCholesky;
  testing::ExpectErrorContains(
      [&] {
        TrainPrior(chol, TinyData().train, TinyData().val, dir.File("c"), false, {}, art, "");
      },
      {"u_param = cholesky", "diagonal"});
  testing::ExpectErrorContains(
      [&] { TrainPrior(spec, TinyData().train, WindowSet{}, dir.File("e"), false, {}, art, ""); },
      {"no validation windows"});
}

TEST(Learners, KtmEngineFeaturesAndParityWithLibTorch) {
  testing::TempDir dir;
  const LearnerSpec spec = TinySpec();
  KtmSpec ktm;
  ktm.references = 20;
  ktm.lengthscale = 0.8;
  const std::string art = dir.File("ktm.h5"), run = dir.File("ktm");
  ASSERT_TRUE(TrainKtm(spec, ktm, TinyData().train, TinyData().val, run, false, {}, art, ""));
  const span::Predictor engine = span::Predictor::Load(art);
  ASSERT_EQ(engine.ktm_references().rows(), 20);
  EXPECT_EQ(engine.ktm_lengthscale(), 0.8);
  EXPECT_EQ(engine.mlp().input_size(), 20);
  const h5::File f = h5::File::Open(art);
  const Eigen::VectorXd mean = f.ReadMatrixD("/normalisation/input_mean").col(0);
  const Eigen::VectorXd std = f.ReadMatrixD("/normalisation/input_std").col(0);
  const Eigen::MatrixXd& refs = engine.ktm_references();

  // The LibTorch net of the best checkpoint.
  span::ModelSpec s;
  s.observed = spec.observed;
  s.predicted = spec.predicted;
  s.basis = spec.basis;
  s.network = spec.network;
  span::Net net(20, spec.network, span::LayoutOf(s));
  LoadCheckpointModel(RunPaths{run}.BestCheckpoint(), net.ptr().get());
  net->eval();

  auto ws = engine.MakeWorkspace();
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 10; ++trial) {
    const Path past = RandomPast(spec.observed, &rng);
    const Eigen::VectorXd q = EgoPast(past);
    Eigen::VectorXd x(20);  // direct: exp(-RMS^2 / (2 l^2)), normalised
    for (int k = 0; k < 20; ++k) {
      const double d2 = (q - refs.row(k).transpose()).squaredNorm() / spec.observed;
      x[k] = (std::exp(-d2 / (2 * 0.8 * 0.8)) - mean[k]) / std[k];
    }
    engine.RawOutput(past, &ws);
    for (int k = 0; k < 20; ++k)
      EXPECT_NEAR(ws.input[k], x[k], 1e-5 * std::max(1.0, std::abs(x[k])));
    torch::NoGradGuard no_grad;
    const auto raw = net->forward(Row(x));
    for (Eigen::Index k = 0; k < ws.raw.size(); ++k) {
      const double a = raw[0][k].item<double>();
      EXPECT_NEAR(ws.raw[k], a, 1e-4 * std::max(1.0, std::abs(a))) << "output " << k;
    }
  }
  // The KTM stage allocates nothing (buffers in the Workspace).
  auto dist = engine.MakeDistribution();
  const Path past = RandomPast(spec.observed, &rng);
  engine.Predict(past, &ws, &dist);
  g_allocations = 0;
  g_counting = true;
  engine.Predict(past, &ws, &dist);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
}

TEST(Learners, NaiveEngineMatchesLibTorch) {
  testing::TempDir dir;
  const LearnerSpec spec = TinySpec();
  NaiveSpec naive;
  naive.hidden = {40, 20, 20};
  const std::string art = dir.File("naive.h5"), run = dir.File("naive");
  ASSERT_TRUE(TrainNaive(spec, naive, TinyData().train, TinyData().val, run, false, {}, art, "x"));
  const NaivePredictor engine = NaivePredictor::Load(art);
  EXPECT_EQ(engine.observed(), 6);
  EXPECT_EQ(engine.predicted(), 8);
  const h5::File f = h5::File::Open(art);
  EXPECT_EQ(f.GetStringAttr("/", "model_type"), "naive_predictor");
  const Eigen::VectorXd mean = f.ReadMatrixD("/normalisation/input_mean").col(0);
  const Eigen::VectorXd std = f.ReadMatrixD("/normalisation/input_std").col(0);
  NaiveNet net(12, naive.hidden, 16);
  LoadCheckpointModel(RunPaths{run}.BestCheckpoint(), net.ptr().get());
  for (double v : ValLosses(run)) EXPECT_TRUE(std::isfinite(v));

  auto ws = engine.MakeWorkspace();
  Path future(8, 2);
  std::mt19937_64 rng(9);
  for (int trial = 0; trial < 10; ++trial) {
    const Path past = RandomPast(6, &rng);
    const Eigen::VectorXd q = EgoPast(past);
    const Eigen::VectorXd x = (q - mean).cwiseQuotient(std);
    torch::NoGradGuard no_grad;
    const auto y = net->forward(Row(x));
    engine.Predict(past, &ws, future);
    // Back to the world frame by hand: rotation to the first->last heading, origin last point.
    const Eigen::Vector2d d = past.row(5) - past.row(0);
    const double c = d.x() / d.norm(), s = d.y() / d.norm();
    for (int k = 0; k < 8; ++k) {
      const double ex = y[0][2 * k].item<double>(), ey = y[0][2 * k + 1].item<double>();
      EXPECT_NEAR(future(k, 0), past(5, 0) + c * ex - s * ey, 1e-4);
      EXPECT_NEAR(future(k, 1), past(5, 1) + s * ex + c * ey, 1e-4);
    }
  }
  const Path past = RandomPast(6, &rng);
  g_allocations = 0;
  g_counting = true;
  engine.Predict(past, &ws, future);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  testing::ExpectErrorContains([&] { engine.Predict(Path::Zero(5, 2), &ws, future); },
                               {"expected 6 observed points, got 5"});
}

/// Weights of every dense layer of an artifact, concatenated.
Eigen::VectorXf AllWeights(const std::string& artifact) {
  const h5::File f = h5::File::Open(artifact);
  std::vector<float> all;
  for (const std::string& layer : f.List("/weights"))
    for (const char* part : {"/weight", "/bias"}) {
      const Eigen::MatrixXf m = f.ReadMatrixF("/weights/" + layer + part);
      all.insert(all.end(), m.data(), m.data() + m.size());
    }
  return Eigen::Map<const Eigen::VectorXf>(all.data(), static_cast<Eigen::Index>(all.size()));
}

TEST(Learners, KtmResumeAfterInterruptEqualsUninterruptedRun) {
  testing::TempDir dir;
  const LearnerSpec spec = TinySpec();
  KtmSpec ktm;
  ktm.references = 12;
  const Data& d = TinyData();
  ASSERT_TRUE(TrainKtm(spec, ktm, d.train, d.val, dir.File("a"), false, {}, dir.File("a.h5"), ""));
  TrainHooks stop;
  stop.continue_after_epoch = [](int epoch) { return epoch < 1; };
  EXPECT_FALSE(
      TrainKtm(spec, ktm, d.train, d.val, dir.File("b"), false, stop, dir.File("b.h5"), ""));
  EXPECT_FALSE(std::filesystem::exists(dir.File("b.h5")));
  ASSERT_TRUE(TrainKtm(spec, ktm, d.train, d.val, dir.File("b"), true, {}, dir.File("b.h5"), ""));
  const Eigen::VectorXf a = AllWeights(dir.File("a.h5")), b = AllWeights(dir.File("b.h5"));
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 0);
  EXPECT_EQ((a - b).cwiseAbs().maxCoeff(), 0.0f) << "resumed run differs";
  EXPECT_EQ(span::Predictor::Load(dir.File("a.h5")).ktm_references(),
            span::Predictor::Load(dir.File("b.h5")).ktm_references());
}

}  // namespace
}  // namespace foresight::constrained
