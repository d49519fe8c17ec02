// Directional maps through LibTorch: engine parity on exported networks, the loss against an
// independent von Mises computation, gradients, a tiny train -> export -> eval run, bad input.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/von_mises.h"
#include "inference/directional/directional_map.h"
#include "inference/prediction/span_predictor.h"
#include "models/directional/directional_net.h"
#include "tests/test_util.h"
#include "training/directional/config.h"
#include "training/directional/pipeline.h"

namespace foresight::directional {
namespace {

FeatureConfig TestFeatureConfig() {
  FeatureConfig f;
  f.x_min = -1;
  f.x_max = 9;
  f.y_min = 0;
  f.y_max = 6;
  f.cells_x = 7;
  f.cells_y = 5;
  f.length_scale = 1.2;
  f.t_min = 0;
  f.t_max = 50;
  f.time_points = 4;
  f.time_length_scale = 12;
  f.cutoff = 5;
  return f;
}

class Parity : public ::testing::TestWithParam<Variant> {};

TEST_P(Parity, EngineMatchesLibTorchOnARandomExportedModel) {
  const FeatureConfig fc = TestFeatureConfig();
  const Features feats(fc);
  torch::manual_seed(5);
  Net net(GetParam(), feats.spatial_size(), 5, 40);
  {
    torch::NoGradGuard no_grad;
    for (auto& p : net->parameters())
      p.add_(0.3 * torch::randn_like(p));  // away from the initialisation
  }
  testing::TempDir dir;
  const std::string path = dir.File("model.h5");
  WriteArtifact(*net, fc, "model: directional\n", 5, path);
  const Map engine = Map::Load(path);
  EXPECT_EQ(engine.variant(), GetParam());
  auto ws = engine.MakeWorkspace();
  LoadedNet reloaded = LoadNetFromArtifact(path);
  net->eval();
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> ux(-3, 11), uy(-2, 8), ut(-10, 60);
  double worst = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const double x = ux(rng), y = uy(rng), t = ut(rng);
    Eigen::VectorXf s(feats.spatial_size()), tm(feats.time_size());
    feats.Spatial(x, y, s);
    feats.Temporal(t, tm);
    torch::NoGradGuard no_grad;
    const auto ts = torch::from_blob(s.data(), {1, s.size()}, torch::kFloat32).clone();
    const auto tt = torch::from_blob(tm.data(), {1, tm.size()}, torch::kFloat32).clone();
    const auto raw = net->forward(ts, tt);
    const auto raw2 = reloaded.net->forward(ts, tt);
    EXPECT_TRUE(torch::equal(raw, raw2));
    engine.RawOutput(x, y, t, &ws);
    for (int k = 0; k < 15; ++k) {
      const double a = raw[0][k].item<double>(), b = ws.raw[k];
      worst = std::max(worst, std::abs(a - b) / std::max(1.0, std::abs(a)));
      EXPECT_NEAR(b, a, 1e-5 * std::max(1.0, std::abs(a)))
          << "output " << k << " at " << x << ", " << y << ", " << t;
    }
    // Decoded mixtures agree too.
    const auto p = DecodeVonMisesHead(raw.to(torch::kFloat64), 5);
    engine.QueryOne(x, y, t, &ws);
    for (int r = 0; r < 5; ++r) {
      EXPECT_NEAR(ws.alpha[r], std::exp(p.log_alpha[0][r].item<double>()), 1e-5);
      EXPECT_NEAR(std::remainder(ws.mu[r] - p.mu[0][r].item<double>(), 2 * M_PI), 0.0, 1e-5);
      EXPECT_NEAR(ws.kappa[r], p.kappa[0][r].item<double>(), 1e-5 * std::max(1.0, ws.kappa[r]));
    }
  }
  RecordProperty("worst_relative_difference", std::to_string(worst));
}

INSTANTIATE_TEST_SUITE_P(Directional, Parity,
                         ::testing::Values(Variant::kSpatiotemporal, Variant::kSpatial),
                         [](const ::testing::TestParamInfo<Variant>& p) {
                           return std::string(VariantName(p.param));
                         });

TEST(DirectionalNet, WrittenOutLstmMatchesTorchLstmAndSparseMatchesDense) {
  const Features feats(TestFeatureConfig());
  torch::manual_seed(9);
  Net net(Variant::kSpatiotemporal, feats.spatial_size(), 4, 24);
  // torch::nn::LSTM with the same parameters on the sequence phi_s * phi_t[k].
  torch::nn::LSTM ref(torch::nn::LSTMOptions(feats.spatial_size(), 24).batch_first(true));
  {
    torch::NoGradGuard no_grad;
    auto mine = net->named_parameters();
    auto theirs = ref->named_parameters();
    for (const char* name : {"weight_ih_l0", "weight_hh_l0", "bias_ih_l0", "bias_hh_l0"})
      theirs[name].copy_(mine[std::string("lstm.") + name]);
  }
  const int B = 16;
  Eigen::VectorXd x = Eigen::VectorXd::Random(B) * 6 + Eigen::VectorXd::Constant(B, 4);
  Eigen::VectorXd y = Eigen::VectorXd::Random(B) * 4 + Eigen::VectorXd::Constant(B, 3);
  Eigen::VectorXd t = Eigen::VectorXd::Random(B) * 30 + Eigen::VectorXd::Constant(B, 25);
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> s(B, feats.spatial_size()),
      tm(B, feats.time_size());
  feats.SpatialBatch(x, y, s);
  feats.TemporalBatch(t, tm);
  const auto ts = torch::from_blob(s.data(), {B, s.cols()}, torch::kFloat32).clone();
  const auto tt = torch::from_blob(tm.data(), {B, tm.cols()}, torch::kFloat32).clone();
  torch::NoGradGuard no_grad;
  const auto seq = tt.unsqueeze(2) * ts.unsqueeze(1);
  const auto out = std::get<0>(ref->forward(seq));
  const auto h = out.select(1, out.size(1) - 1);
  const auto expected = torch::cat(
      {net->alpha_head()->forward(h), net->mu_head()->forward(h), net->kappa_head()->forward(h)},
      1);
  const auto dense = net->forward(ts, tt);
  EXPECT_LT((dense - expected).abs().max().item<float>(), 1e-5f);
  std::vector<std::int64_t> index, offsets;
  std::vector<float> value;
  feats.SpatialSparseBatch(x, y, &index, &value, &offsets);
  EXPECT_LT(index.size(), static_cast<std::size_t>(B * feats.spatial_size()));
  const auto n = static_cast<std::int64_t>(index.size());
  const auto sparse =
      net->forward_sparse(torch::from_blob(index.data(), {n}, torch::kInt64),
                          torch::from_blob(value.data(), {n}, torch::kFloat32),
                          torch::from_blob(offsets.data(), {B + 1}, torch::kInt64), tt);
  EXPECT_LT((sparse - dense).abs().max().item<float>(), 1e-5f);
  Net spatial(Variant::kSpatial, feats.spatial_size(), 4, 0);
  const auto sd = spatial->forward(ts, tt);
  const auto ss =
      spatial->forward_sparse(torch::from_blob(index.data(), {n}, torch::kInt64),
                              torch::from_blob(value.data(), {n}, torch::kFloat32),
                              torch::from_blob(offsets.data(), {B + 1}, torch::kInt64), tt);
  EXPECT_LT((sd - ss).abs().max().item<float>(), 1e-5f);
}

TEST(DirectionalLoss, NllMatchesCoreVonMisesMixture) {
  torch::manual_seed(1);
  const int B = 64, R = 5;
  auto raw = torch::randn({B, 3 * R}, torch::kFloat64) * 2.0;
  raw.narrow(1, 2 * R, R)
      .mul_(3.0);  // log kappa over roughly [-20, 20]: both clamps and large kappa
  const auto theta = (torch::rand({B}, torch::kFloat64) * 2 - 1) * M_PI;
  const auto p = DecodeVonMisesHead(raw, R, 1e6);  // large kappa allowed here
  const auto nll = VonMisesMixtureNll(p, theta);
  for (int b = 0; b < B; ++b) {
    Eigen::VectorXd alpha(R), mu(R), kappa(R);
    for (int r = 0; r < R; ++r) {
      alpha[r] = std::exp(p.log_alpha[b][r].item<double>());
      mu[r] = p.mu[b][r].item<double>();
      kappa[r] = p.kappa[b][r].item<double>();
    }
    const double ref = -VonMisesMixtureLogDensity(theta[b].item<double>(), alpha, mu, kappa);
    EXPECT_NEAR(nll[b].item<double>(), ref, 1e-9 * std::max(1.0, std::abs(ref))) << "sample " << b;
  }
  // log I0 in torch against the core implementation, including kappa where exp overflows.
  for (const double k : {0.0, 1e-8, 0.3, 2.0, 29.0, 31.0, 200.0, 700.0, 1e3, 1e5}) {
    const double t = LogBesselI0(torch::tensor({k}, torch::kFloat64))[0].item<double>();
    EXPECT_NEAR(t, foresight::LogBesselI0(k), 1e-10 * std::max(1.0, k)) << k;
  }
  EXPECT_TRUE(std::isfinite(LogBesselI0(torch::tensor({22026.0f}))[0].item<float>()));
}

TEST(DirectionalLoss, GradientsMatchFiniteDifferencesAndPenaltyIsAdded) {
  torch::manual_seed(3);
  const int B = 8, R = 3;
  auto raw = (torch::randn({B, 3 * R}, torch::kFloat64)).requires_grad_(true);
  const auto theta = (torch::rand({B}, torch::kFloat64) * 2 - 1) * M_PI;
  auto loss_of = [&](const torch::Tensor& r) {
    return VonMisesMixtureNll(DecodeVonMisesHead(r, R), theta).mean();
  };
  const auto loss = loss_of(raw);
  loss.backward();
  const auto grad = raw.grad().clone();
  const double h = 1e-6;
  for (int b = 0; b < B; ++b)
    for (int k = 0; k < 3 * R; ++k) {
      auto plus = raw.detach().clone(), minus = raw.detach().clone();
      plus[b][k] += h;
      minus[b][k] -= h;
      const double fd = (loss_of(plus).item<double>() - loss_of(minus).item<double>()) / (2 * h);
      EXPECT_NEAR(grad[b][k].item<double>(), fd, 1e-6) << b << " " << k;
    }
  // L_reg = mean NLL + lambda_a ||W_a||^2 + lambda_k ||W_k||^2 (+ lambda_m ||W_m||^2, 0 here).
  Net net(Variant::kSpatial, 6, R, 0);
  const auto s = torch::rand({B, 6});
  const auto t = torch::rand({B, 1});
  const auto th = theta.to(torch::kFloat32);
  const Penalty pen{0.01, 0.0, 0.02};
  const double with = Loss(*net, s, t, th, pen).item<double>();
  const double nll =
      VonMisesMixtureNll(DecodeVonMisesHead(net->forward(s, t), R), th).mean().item<double>();
  const double expected = 0.01 * net->alpha_head()->weight.square().sum().item<double>() +
                          0.02 * net->kappa_head()->weight.square().sum().item<double>();
  EXPECT_GT(expected, 0);
  EXPECT_NEAR(with - nll, expected, 1e-5);
  // lambda_mu = 0: the mean head gets no penalty gradient.
  net->zero_grad();
  HeadPenalty(*net, pen).backward();
  EXPECT_EQ(net->mu_head()->weight.grad().abs().max().item<float>(), 0.0f);
  EXPECT_GT(net->alpha_head()->weight.grad().abs().max().item<float>(), 0.0f);
}

ExperimentConfig TinyCrossing() {
  ExperimentConfig c;
  c.data.format = Source::kCrossing;
  c.data.crossing.flow.num_tracks = 120;
  c.data.crossing.flow.duration = 60;
  c.features.x_min = 0;
  c.features.x_max = 10;
  c.features.y_min = 0;
  c.features.y_max = 10;
  c.features.cells_x = 5;
  c.features.cells_y = 5;
  c.features.length_scale = 2.2;
  c.features.t_min = 0;
  c.features.t_max = 60;
  c.features.time_points = 3;
  c.features.time_length_scale = 15;
  c.network.components = 3;
  c.network.hidden = 16;
  c.train.epochs = 3;
  c.train.batch_size = 64;
  c.train.learning_rate = 5e-3;
  c.train.progress = ProgressStyle::kNone;
  c.eval.folds = 2;
  c.eval.plot_trajectories = 3;
  c.eval.plot_steps = 20;
  return c;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(DirectionalPipeline, TinyCrossingTrainExportEval) {
  testing::TempDir dir;
  const ExperimentConfig c = TinyCrossing();
  const RunResult r = RunExperiment(c, dir.path(), false);
  EXPECT_FALSE(r.interrupted);
  EXPECT_EQ(r.report.folds_evaluated, 2);
  for (const char* m :
       {"spatiotemporal", "spatial", "grid_um", "grid_mm", "grid_um_dense", "grid_mm_dense"}) {
    const MethodMetrics* mm = r.report.Find(m);
    ASSERT_NE(mm, nullptr) << m;
    EXPECT_EQ(mm->al.size(), 2u);
    EXPECT_TRUE(std::isfinite(mm->MeanAl()) && mm->MeanAl() > 0) << m;
    EXPECT_TRUE(std::isfinite(mm->MeanMre()) && mm->MeanMre() >= 0 && mm->MeanMre() <= M_PI) << m;
  }
  const std::string json = ReadFile(dir.File("eval.json"));
  for (const char* key : {"\"spatiotemporal\": {\"al\": ", "\"spatial\": {\"al\": ",
                          "\"grid_um\": {\"al\": ", "\"grid_mm\": {\"al\": ", "\"mre\": "})
    EXPECT_NE(json.find(key), std::string::npos) << key << " not in " << json;
  EXPECT_EQ(json.find("null"), std::string::npos);
  EXPECT_NE(ReadFile(dir.File("eval.csv")).find("grid_mm,1,"), std::string::npos);
  const Map m = Map::Load(dir.File("model.h5"));
  EXPECT_EQ(m.variant(), Variant::kSpatiotemporal);
  EXPECT_EQ(m.components(), 3);
  EXPECT_EQ(Map::Load(dir.File("model_spatial.h5")).variant(), Variant::kSpatial);
  for (const char* f : {"plots/directions.png", "plots/trajectories.png",
                        "folds/1/spatial/metrics.csv", "config.yaml"})
    EXPECT_TRUE(std::filesystem::exists(dir.File(f))) << f;
  // A fresh start refuses the used directory; resume finds everything done and gives the same
  // report.
  testing::ExpectErrorContains([&] { RunExperiment(c, dir.path(), false); },
                               {"already holds a run"});
  const RunResult again = RunExperiment(c, dir.path(), true);
  EXPECT_DOUBLE_EQ(again.report.Find("spatiotemporal")->MeanAl(),
                   r.report.Find("spatiotemporal")->MeanAl());
  ExperimentConfig other = c;
  other.train.epochs = 4;
  testing::ExpectErrorContains([&] { RunExperiment(other, dir.path(), true); }, {"differs"});
}

TEST(DirectionalPipeline, BadInput) {
  testing::TempDir dir;
  ExperimentConfig c = TinyCrossing();
  c.data.format = Source::kGridCsv;
  // NaN coordinates.
  testing::WriteText(dir.File("nan.csv"),
                     "x_m,y_m,orientation_raw_rad,path_id\n1,2,0,0\nnan,2.5,0,0\n1,3,0,0\n");
  c.data.file = dir.File("nan.csv");
  testing::ExpectErrorContains([&] { LoadSamples(c); }, {"nan.csv"});
  // No data rows.
  testing::WriteText(dir.File("empty.csv"), "x_m,y_m,orientation_raw_rad,path_id\n");
  c.data.file = dir.File("empty.csv");
  testing::ExpectErrorContains([&] { RunExperiment(c, dir.File("run"), false); }, {"empty.csv"});
  // Config errors name the key.
  testing::ExpectErrorContains(
      [&] {
        config::ExperimentConfigFromYaml<ExperimentConfig>(
            "model: directional\ndata: {format: grid_csv}\n", "x.yaml");
      },
      {"x.yaml", "data.file"});
  testing::ExpectErrorContains(
      [&] {
        config::ExperimentConfigFromYaml<ExperimentConfig>(
            "model: directional\nfeatures: {cells: 3}\n", "x.yaml");
      },
      {"x.yaml", "features.cells"});
  testing::ExpectErrorContains(
      [&] {
        config::ExperimentConfigFromYaml<ExperimentConfig>("model: span_predictor\n", "x.yaml");
      },
      {"'model'", "directional"});
  // Artifacts of the other kind, both ways.
  const std::string span = dir.File("span.h5");
  testing::WriteRandomSpanArtifact(span, {});
  testing::ExpectErrorContains([&] { LoadNetFromArtifact(span); }, {"expected 'directional_map'"});
  Net net(Variant::kSpatial, 35, 5, 0);
  const std::string dm = dir.File("dm.h5");
  WriteArtifact(*net, TestFeatureConfig(), "model: directional\n", 0, dm);
  testing::ExpectErrorContains([&] { span::Predictor::Load(dm); }, {"expected 'span_predictor'"});
  FeatureConfig unresolved = TestFeatureConfig();
  unresolved.auto_extent = true;
  testing::ExpectErrorContains([&] { WriteArtifact(*net, unresolved, "", 0, dm); }, {"unresolved"});
}

TEST(DirectionalConfigs, ShippedConfigsLoad) {
  const char* src = std::getenv("FORESIGHT_SOURCE_DIR");
  ASSERT_NE(src, nullptr);
  for (const char* name : {"p1", "p2", "crossing", "edinburgh"})
    EXPECT_NO_THROW(config::LoadExperimentConfig<ExperimentConfig>(
        std::string(src) + "/configs/directional/" + name + ".yaml", {}))
        << name;
}

}  // namespace
}  // namespace foresight::directional
