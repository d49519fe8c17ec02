// Covariance calibration of the SPAN predictor (training/span/calibration.h): the fitted scale
// against the closed form and a dense search, the scaled NLL against the engine's own density, and
// the export step that writes the scale.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "datasets/synthetic_pedestrians.h"
#include "datasets/windows.h"
#include "inference/prediction/span_predictor.h"
#include "tests/test_util.h"
#include "training/span/calibration.h"
#include "training/span/eval.h"
#include "training/span/pipeline.h"

namespace foresight::span {
namespace {

WindowSet SyntheticWindows(int tracks) {
  SyntheticPedestrianConfig c;
  c.num_tracks = tracks;
  c.seed = 5;
  return MakeWindows(GenerateSyntheticPedestrians(c), WindowConfig{8, 12, 4});
}

std::string RandomArtifact(const testing::TempDir& dir, int components, double scale) {
  testing::RandomSpanSpec spec;
  spec.components = components;
  const std::string path = dir.File("r" + std::to_string(components) + ".h5");
  testing::WriteRandomSpanArtifact(path, spec);
  if (scale != 1.0) testing::OverwriteAttr(path, "/model", "covariance_scale", scale);
  return path;
}

// Mean over the windows' points of -log p(true position) computed by the engine itself.
double EngineNll(const Predictor& model, const WindowSet& w) {
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(w.observed, 2);
  double sum = 0;
  for (int n = 0; n < w.size(); ++n) {
    for (int i = 0; i < w.observed; ++i) past.row(i) = w.Past(n, i).transpose();
    model.Predict(past, &ws, &dist);
    for (int k = 0; k < w.predicted; ++k)
      sum -= dist.LogDensity((k + 1) * w.seconds_per_step, w.Future(n, k));
  }
  return sum / (static_cast<double>(w.size()) * w.predicted);
}

TEST(SpanCalibration, OneComponentScaleIsTheClosedForm) {
  testing::TempDir dir;
  const WindowSet w = SyntheticWindows(30);
  ASSERT_GT(w.size(), 20);
  const Predictor model = Predictor::Load(RandomArtifact(dir, 1, 1.0));
  const std::vector<PointTerms> terms = CovarianceScaleTerms(model, w);
  ASSERT_EQ(terms.size(), static_cast<std::size_t>(w.size() * w.predicted));
  // d/dc [log c + d2 / (2c)] = 0 at c = d2 / 2, averaged over the points.
  double mean_d2 = 0;
  for (const PointTerms& p : terms) mean_d2 += p[0].d2;
  mean_d2 /= static_cast<double>(terms.size());
  EXPECT_NEAR(FitCovarianceScale(terms), mean_d2 / 2, 1e-6 * mean_d2);
}

TEST(SpanCalibration, ScaledNllIsTheEngineNllOfTheScaledArtifact) {
  testing::TempDir dir;
  const WindowSet w = SyntheticWindows(20);
  for (const int components : {1, 3}) {
    const std::vector<PointTerms> terms =
        CovarianceScaleTerms(Predictor::Load(RandomArtifact(dir, components, 1.0)), w);
    for (const double c : {0.3, 1.0, 4.0}) {
      const Predictor scaled = Predictor::Load(RandomArtifact(dir, components, c));
      EXPECT_DOUBLE_EQ(scaled.covariance_scale(), c);
      const double engine = EngineNll(scaled, w);
      EXPECT_NEAR(ScaledNll(terms, c), engine, 1e-9 * std::max(1.0, std::abs(engine)))
          << components << " components, c = " << c;
      // The terms do not depend on the scale stored in the artifact they come from.
      const std::vector<PointTerms> again = CovarianceScaleTerms(scaled, w);
      EXPECT_NEAR(again[7][0].d2, terms[7][0].d2, 1e-9 * terms[7][0].d2);
    }
  }
}

TEST(SpanCalibration, MixtureScaleIsTheMinimumOfADenseSearch) {
  testing::TempDir dir;
  const WindowSet w = SyntheticWindows(20);
  const std::vector<PointTerms> terms =
      CovarianceScaleTerms(Predictor::Load(RandomArtifact(dir, 3, 1.0)), w);
  const double c = FitCovarianceScale(terms);
  double best_c = 0, best = INFINITY;
  for (double log10_c = -3; log10_c <= 3; log10_c += 1e-3) {
    const double v = ScaledNll(terms, std::pow(10.0, log10_c));
    if (v < best) {
      best = v;
      best_c = std::pow(10.0, log10_c);
    }
  }
  EXPECT_NEAR(std::log(c), std::log(best_c), 3e-3);
  EXPECT_LE(ScaledNll(terms, c), best + 1e-9);
  EXPECT_LE(ScaledNll(terms, c), ScaledNll(terms, 1.0));
}

TEST(SpanCalibration, EngineScalesEveryCovarianceAndKeepsTheMean) {
  testing::TempDir dir;
  const Predictor plain = Predictor::Load(RandomArtifact(dir, 2, 1.0));
  const Predictor scaled = Predictor::Load(RandomArtifact(dir, 2, 2.5));
  auto ws = plain.MakeWorkspace();
  auto a = plain.MakeDistribution(), b = scaled.MakeDistribution();
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(8, 2);
  for (int i = 0; i < 8; ++i) past.row(i) << 0.5 * i, 0.1 * i * i;
  plain.Predict(past, &ws, &a);
  scaled.Predict(past, &ws, &b);
  Eigen::Vector2d ma, mb;
  Eigen::Matrix2d ca, cb;
  for (int r = 0; r < 2; ++r) {
    EXPECT_DOUBLE_EQ(a.alpha(r), b.alpha(r));
    for (const double t : {0.4, 2.0, 4.8}) {
      a.Position(t, r, &ma, &ca);
      b.Position(t, r, &mb, &cb);
      EXPECT_TRUE(testing::MatricesNear(mb, ma, 1e-12));
      EXPECT_TRUE(testing::MatricesNear(cb, 2.5 * ca, 1e-9 * ca.norm()));
    }
  }
}

TEST(SpanCalibration, LoadRefusesAScaleOutOfRange) {
  testing::TempDir dir;
  for (const double bad : {0.0, -1.0, 1e9, std::nan("")}) {
    const std::string path = RandomArtifact(dir, 1, bad);
    std::ostringstream value;
    value << bad;
    testing::ExpectErrorContains([&] { (void)Predictor::Load(path); },
                                 {path, "/model/covariance_scale is " + value.str()});
  }
}

TEST(SpanCalibration, ExportFitsTheScaleOnValidationWindows) {
  testing::TempDir dir;
  ExperimentConfig c;
  c.data.synthetic.num_tracks = 150;
  c.network.hidden = {16, 16};
  c.basis.num_centres = 6;
  c.train.epochs = 2;
  c.train.batch_size = 64;
  c.train.progress = ProgressStyle::kNone;
  c.calibrate_covariance = true;
  TrainRun(c, dir.path(), false);
  const std::string artifact = ExportRun(dir.path());
  const Predictor model = Predictor::Load(artifact);
  EXPECT_NE(model.covariance_scale(), 1.0);
  EXPECT_FALSE(std::filesystem::exists(dir.File("model.uncalibrated.h5")));
  // Evaluation reports the artifact's scale.
  c.eval.plot_tracks = 0;
  EXPECT_EQ(Evaluate(c, artifact, dir.path()).covariance_scale, model.covariance_scale());
  // The fitted scale is the one the validation windows choose, independently recomputed.
  const TrackSplit split = LoadPedestrianSplits(c.data, static_cast<std::uint64_t>(c.seed));
  const std::vector<PointTerms> terms =
      CovarianceScaleTerms(model, MakeWindows(split.val, c.windows));
  EXPECT_NEAR(model.covariance_scale(), FitCovarianceScale(terms), 1e-6 * model.covariance_scale());
  EXPECT_LT(ScaledNll(terms, model.covariance_scale()), ScaledNll(terms, 1.0));
}

}  // namespace
}  // namespace foresight::span
