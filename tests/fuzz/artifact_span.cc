// Fuzz target: SpanPredictor::Load (raw-input and KTM variants) and NaivePredictor::Load on edited
// valid artifacts written by the engines' own Save (tests/fuzz/h5_mutator.h); the first input byte
// picks the artifact. A model that loads must predict finite values for a finite past.
#include <cmath>
#include <random>

#include "inference/prediction/naive_predictor.h"
#include "inference/prediction/span_predictor.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/h5_mutator.h"

namespace {

using foresight::DenseLayer;
using foresight::Mlp;

constexpr int kObserved = 3, kPredicted = 4;

Mlp RandomMlp(const std::vector<int>& widths, std::mt19937_64* rng) {
  std::normal_distribution<float> n01;
  std::vector<DenseLayer> layers;
  for (std::size_t i = 0; i + 1 < widths.size(); ++i) {
    DenseLayer l;
    l.weight =
        Eigen::MatrixXf::NullaryExpr(widths[i + 1], widths[i], [&] { return 0.3f * n01(*rng); });
    l.bias = Eigen::VectorXf::NullaryExpr(widths[i + 1], [&] { return 0.1f * n01(*rng); });
    layers.push_back(std::move(l));
  }
  return Mlp(std::move(layers));
}

std::vector<std::uint8_t> SpanBase(bool ktm) {
  using namespace foresight;
  std::mt19937_64 rng(ktm ? 2 : 1);
  span::PredictorWeights w;
  w.observed = kObserved;
  w.predicted = kPredicted;
  w.seconds_per_step = 0.4;
  w.residual_to_constant_velocity = ktm;
  w.layout = HeadLayout{3, 2, ktm ? UParam::kDiagonal : UParam::kCholesky};
  w.basis_centres = Eigen::VectorXd::LinSpaced(3, 0.0, kPredicted * 0.4);
  w.basis_gamma = 1.0;
  int in = 2 * kObserved;
  if (ktm) {
    w.ktm_references = Eigen::MatrixXd::Random(4, 2 * kObserved);
    w.ktm_lengthscale = 0.7;
    in = 4;
  }
  w.input_mean = Eigen::VectorXd::Constant(in, 0.1);
  w.input_std = Eigen::VectorXd::Constant(in, 2.0);
  w.layer_names = {"mlp.0", "head"};
  w.mlp = RandomMlp({in, 5, w.layout.Total()}, &rng);
  const std::string path = fuzz::ScratchPath(ktm ? "base_span_ktm.h5" : "base_span.h5");
  span::Predictor::Save(path, w, "model: span_predictor\n", 0);
  return fuzz::ReadFileBytes(path);
}

std::vector<std::uint8_t> NaiveBase() {
  using namespace foresight;
  std::mt19937_64 rng(3);
  NaivePredictorWeights w;
  w.observed = kObserved;
  w.predicted = kPredicted;
  w.seconds_per_step = 0.4;
  w.input_mean = Eigen::VectorXd::Constant(2 * kObserved, 0.1);
  w.input_std = Eigen::VectorXd::Constant(2 * kObserved, 2.0);
  w.layer_names = {"mlp.0", "head"};
  w.mlp = RandomMlp({2 * kObserved, 5, 2 * kPredicted}, &rng);
  const std::string path = fuzz::ScratchPath("base_naive.h5");
  NaivePredictor::Save(path, w, "model: naive_predictor\n", 0);
  return fuzz::ReadFileBytes(path);
}

Eigen::Matrix<double, Eigen::Dynamic, 2> Past(int n) {
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(n, 2);
  for (int i = 0; i < n; ++i) past.row(i) << 1.0 + 0.5 * i, 2.0 - 0.1 * i * i;
  return past;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace foresight;
  static const std::vector<std::uint8_t> bases[] = {SpanBase(false), SpanBase(true), NaiveBase()};
  fuzz::ByteReader in(data, size);
  const int kind = in.Byte() % 3;
  const std::string path = fuzz::WriteScratch("span.h5", bases[kind].data(), bases[kind].size());
  fuzz::MutateH5(path, &in);
  fuzz::ExpectCleanError(path, [&] {
    if (kind < 2) {
      const span::Predictor model = span::Predictor::Load(path);
      auto ws = model.MakeWorkspace();
      auto out = model.MakeDistribution();
      model.Predict(Past(model.observed()), &ws, &out);
      bool finite = out.MeanPosition(1.0).allFinite();
      for (int r = 0; r < out.components(); ++r)
        finite = finite && std::isfinite(out.alpha(r)) && out.mean(r).allFinite() &&
                 out.chol_u(r).allFinite() && out.chol_v(r).allFinite();
      Eigen::Vector2d mean;
      Eigen::Matrix2d cov;
      out.Position(0.8, 0, &mean, &cov);
      finite = finite && mean.allFinite() && cov.allFinite() && out.velocity().allFinite();
      fuzz::ExpectFiniteAnswer(finite, path, "the predicted distribution");
    } else {
      const NaivePredictor model = NaivePredictor::Load(path);
      auto ws = model.MakeWorkspace();
      Eigen::Matrix<double, Eigen::Dynamic, 2> future(model.predicted(), 2);
      model.Predict(Past(model.observed()), &ws, future);
      fuzz::ExpectFiniteAnswer(future.allFinite(), path, "the predicted future");
    }
  });
  return 0;
}
