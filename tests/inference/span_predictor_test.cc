// Engine tests that need no LibTorch: artifacts are written with random weights.

#include "inference/prediction/span_predictor.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <atomic>
#include <cmath>
#include <new>

#include "core/h5.h"
#include "inference/engine/artifact.h"
#include "tests/test_util.h"

// Counts heap allocations while armed (the no-allocation proof).
#include "tests/alloc_counter.h"  // replaces operator new: one per binary

namespace foresight::span {
namespace {

Eigen::Matrix<double, Eigen::Dynamic, 2> Walk(int p, double heading, double speed,
                                              Eigen::Vector2d start) {
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(p, 2);
  for (int i = 0; i < p; ++i)
    past.row(i) = (start + 0.4 * i * speed * Eigen::Vector2d(std::cos(heading), std::sin(heading)) +
                   0.02 * Eigen::Vector2d(std::sin(3.0 * i), std::cos(5.0 * i)))
                      .transpose();
  return past;
}

class SpanEngine : public ::testing::TestWithParam<testing::RandomSpanSpec> {
 protected:
  void SetUp() override {
    path_ = dir_.File("model.h5");
    testing::WriteRandomSpanArtifact(path_, GetParam());
  }
  testing::TempDir dir_;
  std::string path_;
};

TEST_P(SpanEngine, EvaluationAllocatesNothingAfterSetUp) {
  const Predictor model = Predictor::Load(path_);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  const auto past = Walk(model.observed(), 0.7, 1.2, {1, 2});
  Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(12, 0.4, 4.8);
  Eigen::Matrix<double, Eigen::Dynamic, 2> path(12, 2);
  std::mt19937_64 rng(1);
  std::vector<TrajectoryDistribution> outs(4, model.MakeDistribution());
  Eigen::MatrixXd batch(4, 2 * model.observed());
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < model.observed(); ++i)
      batch.row(k).segment<2>(2 * i) = past.row(i) + Eigen::RowVector2d(k, 0);
  model.Predict(past, &ws, &dist);  // warm-up
  g_allocations = 0;
  g_counting = true;
  double sink = 0;
  for (int rep = 0; rep < 10; ++rep) {
    model.Predict(past, &ws, &dist);
    Eigen::Vector2d mu;
    Eigen::Matrix2d cov;
    dist.Position(2.0, 0, &mu, &cov);
    sink += mu.sum() + cov.sum() + dist.MeanPosition(1.0).sum() + dist.LogDensity(3.0, mu);
    dist.SamplePath(times, &rng, path);
    model.PredictBatch(batch, &ws, &outs);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0) << "heap allocations on the evaluation path";
  EXPECT_TRUE(std::isfinite(sink));
}

TEST_P(SpanEngine, PredictionsAreRotationAndTranslationEquivariant) {
  if (!GetParam().rotate) GTEST_SKIP() << "model is not in the ego frame";
  const Predictor model = Predictor::Load(path_);
  auto ws = model.MakeWorkspace();
  auto a = model.MakeDistribution(), b = model.MakeDistribution();
  const auto past = Walk(model.observed(), 0.3, 1.1, {0, 0});
  const double angle = 1.1;
  Eigen::Matrix2d rot;
  rot << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  const Eigen::Vector2d shift(5, -3);
  Eigen::Matrix<double, Eigen::Dynamic, 2> moved = past;
  for (int i = 0; i < past.rows(); ++i)
    moved.row(i) = (rot * past.row(i).transpose() + shift).transpose();
  model.Predict(past, &ws, &a);
  model.Predict(moved, &ws, &b);
  for (double t : {0.4, 2.0, 4.8}) {
    for (int r = 0; r < a.components(); ++r) {
      Eigen::Vector2d ma, mb;
      Eigen::Matrix2d ca, cb;
      a.Position(t, r, &ma, &ca);
      b.Position(t, r, &mb, &cb);
      EXPECT_LT((rot * ma + shift - mb).norm(), 1e-4);
      EXPECT_LT((rot * ca * rot.transpose() - cb).norm(), 1e-4 * (1 + ca.norm()));
    }
  }
}

TEST_P(SpanEngine, PositionAndSamplesAgreeWithTheMatrixNormal) {
  const Predictor model = Predictor::Load(path_);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  model.Predict(Walk(model.observed(), -2.0, 0.9, {3, 3}), &ws, &dist);
  double alpha_sum = 0;
  for (int r = 0; r < dist.components(); ++r) alpha_sum += dist.alpha(r);
  EXPECT_NEAR(alpha_sum, 1.0, 1e-12);
  const double t = 2.4;
  const Eigen::VectorXd phi = model.basis().Evaluate(t);
  // Per component: engine Position == core MatrixNormal::Position (+ origin).
  for (int r = 0; r < dist.components(); ++r) {
    Eigen::Vector2d mu, mu_ref;
    Eigen::Matrix2d cov, cov_ref;
    dist.Position(t, r, &mu, &cov);
    dist.Component(r).Position(phi, &mu_ref, &cov_ref);
    EXPECT_LT((mu - (mu_ref + dist.origin() + t * dist.velocity())).norm(), 1e-12);
    EXPECT_LT((cov - cov_ref).norm(), 1e-12 * (1 + cov.norm()));
  }
  // Sampled positions match the mixture's first two moments.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  for (int r = 0; r < dist.components(); ++r) {
    Eigen::Vector2d mu;
    Eigen::Matrix2d cov;
    dist.Position(t, r, &mu, &cov);
    mean += dist.alpha(r) * mu;
    second += dist.alpha(r) * (cov + mu * mu.transpose());
  }
  const Eigen::Matrix2d cov_mix = second - mean * mean.transpose();
  Eigen::Vector2d moment_mean;
  Eigen::Matrix2d moment_cov;
  dist.MixturePosition(t, &moment_mean, &moment_cov);
  EXPECT_LT((moment_mean - mean).norm(), 1e-12 * (1 + mean.norm()));
  EXPECT_LT((moment_cov - cov_mix).norm(), 1e-12 * (1 + cov_mix.norm()));
  std::mt19937_64 rng(5);
  Eigen::VectorXd times(1);
  times << t;
  Eigen::Matrix<double, Eigen::Dynamic, 2> path(1, 2);
  const int n = 40000;
  Eigen::Vector2d s1 = Eigen::Vector2d::Zero();
  Eigen::Matrix2d s2 = Eigen::Matrix2d::Zero();
  for (int i = 0; i < n; ++i) {
    dist.SamplePath(times, &rng, path);
    const Eigen::Vector2d x = path.row(0).transpose();
    s1 += x;
    s2 += x * x.transpose();
  }
  const Eigen::Vector2d emp_mean = s1 / n;
  const Eigen::Matrix2d emp_cov = s2 / n - emp_mean * emp_mean.transpose();
  const double scale = std::sqrt(cov_mix.trace());
  EXPECT_LT((emp_mean - mean).norm(), 0.03 * scale + 1e-9);
  EXPECT_LT((emp_cov - cov_mix).norm(), 0.05 * cov_mix.norm() + 1e-12);
  EXPECT_LT((dist.MeanPosition(t) - mean).norm(), 1e-9);
}

TEST_P(SpanEngine, BatchEqualsSingleCalls) {
  const Predictor model = Predictor::Load(path_);
  auto ws = model.MakeWorkspace();
  const int p = model.observed();
  Eigen::MatrixXd batch(3, 2 * p);
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 2>> pasts;
  for (int k = 0; k < 3; ++k) {
    pasts.push_back(Walk(p, 0.5 * k, 1.0 + 0.1 * k, {k, -k}));
    for (int i = 0; i < p; ++i) batch.row(k).segment<2>(2 * i) = pasts.back().row(i);
  }
  std::vector<TrajectoryDistribution> outs(3, model.MakeDistribution());
  model.PredictBatch(batch, &ws, &outs);
  auto single = model.MakeDistribution();
  for (int k = 0; k < 3; ++k) {
    model.Predict(pasts[static_cast<std::size_t>(k)], &ws, &single);
    EXPECT_EQ(single.MeanPosition(3.0), outs[static_cast<std::size_t>(k)].MeanPosition(3.0));
  }
}

INSTANTIATE_TEST_SUITE_P(
    Heads, SpanEngine,
    ::testing::Values(
        testing::RandomSpanSpec{},
        testing::RandomSpanSpec{8, 12, 6, 3, UParam::kDiagonal, {16}, 0.4, true, 4, true},
        testing::RandomSpanSpec{5, 10, 4, 2, UParam::kCholesky, {8, 8, 8}, 0.1, false, 9}),
    [](const ::testing::TestParamInfo<testing::RandomSpanSpec>& p) {
      return "R" + std::to_string(p.param.components) + "_" + UParamName(p.param.u_param) +
             (p.param.rotate ? "_ego" : "_world") + (p.param.residual_cv ? "_cv" : "");
    });

TEST(SpanEngineErrors, BadInputIsAClearError) {
  testing::TempDir dir;
  const std::string path = dir.File("model.h5");
  testing::WriteRandomSpanArtifact(path, {});
  const Predictor model = Predictor::Load(path);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  Eigen::Matrix<double, Eigen::Dynamic, 2> past = Walk(8, 0, 1, {0, 0});
  past(3, 1) = NAN;
  testing::ExpectErrorContains([&] { model.Predict(past, &ws, &dist); }, {"NaN"});
  testing::ExpectErrorContains(
      [&] {
        model.Predict(Walk(5, 0, 1, {0, 0}), &ws, &dist);
      },
      {"expected 8 observed points, got 5"});
}

TEST(SpanEngineErrors, OutputOfAnotherLayoutIsAnError) {
  testing::TempDir dir;
  testing::WriteRandomSpanArtifact(dir.File("a.h5"), {8, 12, 6, 1});
  testing::WriteRandomSpanArtifact(dir.File("b.h5"), {8, 12, 6, 3});
  testing::WriteRandomSpanArtifact(dir.File("c.h5"), {8, 12, 4, 1});
  const Predictor a = Predictor::Load(dir.File("a.h5"));
  auto ws = a.MakeWorkspace();
  const auto past = Walk(8, 0, 1, {0, 0});
  for (const char* other : {"b.h5", "c.h5"}) {
    auto dist = Predictor::Load(dir.File(other)).MakeDistribution();
    testing::ExpectErrorContains([&] { a.Predict(past, &ws, &dist); },
                                 {"output distribution has", "the model predicts 1 over 6"});
    std::vector<TrajectoryDistribution> outs{a.MakeDistribution(), dist};
    Eigen::MatrixXd batch(2, 16);
    batch.row(0) = batch.row(1) =
        Eigen::Map<const Eigen::RowVectorXd>(Eigen::MatrixXd(past.transpose()).data(), 16);
    testing::ExpectErrorContains([&] { a.PredictBatch(batch, &ws, &outs); },
                                 {"output distribution has"});
  }
  TrajectoryDistribution empty;
  testing::ExpectErrorContains([&] { a.Predict(past, &ws, &empty); },
                               {"0 components over 0 basis functions"});
}

TEST(SpanEngineErrors, TruncatedForeignAndWrongTypeArtifacts) {
  testing::TempDir dir;
  const std::string path = dir.File("model.h5");
  testing::WriteRandomSpanArtifact(path,
                                   {8, 12, 6, 1, UParam::kCholesky, {256, 256}, 0.4, true, 1});
  {
    std::string copy = dir.File("copy.h5");
    std::filesystem::copy_file(path, copy);
    testing::Truncate(copy, std::filesystem::file_size(copy) / 2);
    EXPECT_THROW(Predictor::Load(copy), Error);
  }
  testing::WriteText(dir.File("text.h5"), "not an artifact");
  testing::ExpectErrorContains([&] { Predictor::Load(dir.File("text.h5")); }, {"text.h5"});
  {
    h5::File f = h5::File::Create(dir.File("map.h5"));
    Artifact::WriteHeader(&f, "fast_bhm", "model: fast_bhm\n", 0);
  }
  testing::ExpectErrorContains([&] { Predictor::Load(dir.File("map.h5")); },
                               {"map.h5", "'fast_bhm'", "expected 'span_predictor'"});
  {
    h5::File f = h5::File::Create(dir.File("future.h5"));
    Artifact::WriteHeader(&f, kModelType, "", 0);
    f.SetAttr("/", "format_version", std::int64_t{99});
  }
  testing::ExpectErrorContains([&] { Predictor::Load(dir.File("future.h5")); },
                               {"format_version 99"});
}

// Issue 18, defect 7: edited attributes are refused with the file, the attribute and the value,
// never narrowed or accepted as NaN.
TEST(SpanEngineErrors, EditedAttributesAreRefusedWithFileAndValue) {
  testing::TempDir dir;
  const std::string good = dir.File("model.h5");
  testing::WriteRandomSpanArtifact(good, {});
  auto edited = [&](const std::string& name, auto value) {
    const std::string path = dir.File(name + ".h5");
    std::filesystem::copy_file(good, path, std::filesystem::copy_options::overwrite_existing);
    testing::OverwriteAttr(path, "/model", name, value);
    return path;
  };
  const std::string wide = edited("observed", (std::int64_t{1} << 32) + 8);
  testing::ExpectErrorContains([&] { Predictor::Load(wide); },
                               {wide, "/model/observed", "4294967304"});
  const std::string step = edited("seconds_per_step", std::nan(""));
  testing::ExpectErrorContains([&] { Predictor::Load(step); }, {step, "seconds_per_step", "nan"});
  const std::string gamma = edited("basis_gamma", -1.0);
  testing::ExpectErrorContains([&] { Predictor::Load(gamma); }, {gamma, "basis_gamma", "-1"});
  const std::string many = edited("components", std::int64_t{1} << 40);
  testing::ExpectErrorContains([&] { Predictor::Load(many); }, {many, "components"});
}

// Fuzz finding (tests/fuzz/corpus/span_artifact/regress_subnormal_input_std): a subnormal
// /normalisation/input_std entry passed "> 0" and the model answered NaN for a finite past.
TEST(SpanEngineErrors, SubnormalInputStdIsRefused) {
  testing::TempDir dir;
  const std::string path = dir.File("model.h5");
  testing::WriteRandomSpanArtifact(path, {});
  {
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hid_t ds = H5Dopen2(file, "/normalisation/input_std", H5P_DEFAULT);
    std::vector<double> std_values(16, 2.0);  // observed = 8: [16]
    std_values[5] = 4.8e-322;
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, std_values.data()), 0);
    H5Dclose(ds);
    H5Fclose(file);
  }
  testing::ExpectErrorContains([&] { Predictor::Load(path); },
                               {path, "/normalisation/input_std[5]", ">= 1e-6"});
}

// Fuzz finding (tests/fuzz/corpus/span_artifact/regress_huge_input_mean): input_mean 1.8e162
// overflowed the float network input and the model answered NaN.
TEST(SpanEngineErrors, HugeInputMeanIsRefused) {
  testing::TempDir dir;
  const std::string path = dir.File("model.h5");
  testing::WriteRandomSpanArtifact(path, {});
  {
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hid_t ds = H5Dopen2(file, "/normalisation/input_mean", H5P_DEFAULT);
    std::vector<double> mean_values(16, 0.0);
    mean_values[3] = 1.76e162;
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, mean_values.data()),
              0);
    H5Dclose(ds);
    H5Fclose(file);
  }
  testing::ExpectErrorContains([&] { Predictor::Load(path); },
                               {path, "/normalisation/input_mean[3]", "1.76e+162"});
}

}  // namespace
}  // namespace foresight::span
