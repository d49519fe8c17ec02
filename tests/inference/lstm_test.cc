// The Eigen LSTM layer against a hand-written double-precision reference of PyTorch's equations.

#include "inference/engine/lstm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/h5.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

LstmWeights RandomWeights(int in, int h, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> n(0.0f, 0.5f);
  LstmWeights w;
  w.weight_ih = Eigen::MatrixXf::NullaryExpr(4 * h, in, [&] { return n(rng); });
  w.weight_hh = Eigen::MatrixXf::NullaryExpr(4 * h, h, [&] { return n(rng); });
  w.bias_ih = Eigen::VectorXf::NullaryExpr(4 * h, [&] { return n(rng); });
  w.bias_hh = Eigen::VectorXf::NullaryExpr(4 * h, [&] { return n(rng); });
  return w;
}

/// Reference: i, f, g, o gates written out one unit at a time, in double.
Eigen::VectorXd ReferenceLstm(const LstmWeights& w, const Eigen::MatrixXd& seq) {
  const int h = static_cast<int>(w.weight_hh.cols());
  Eigen::VectorXd hs = Eigen::VectorXd::Zero(h), cs = Eigen::VectorXd::Zero(h);
  auto sig = [](double v) { return 1.0 / (1.0 + std::exp(-v)); };
  for (Eigen::Index k = 0; k < seq.rows(); ++k) {
    Eigen::VectorXd hn(h), cn(h);
    for (int j = 0; j < h; ++j) {
      double pre[4];
      for (int gate = 0; gate < 4; ++gate) {
        const int row = gate * h + j;
        double s = static_cast<double>(w.bias_ih[row]) + static_cast<double>(w.bias_hh[row]);
        for (Eigen::Index i = 0; i < seq.cols(); ++i)
          s += static_cast<double>(w.weight_ih(row, i)) * seq(k, i);
        for (int i = 0; i < h; ++i) s += static_cast<double>(w.weight_hh(row, i)) * hs[i];
        pre[gate] = s;
      }
      const double ig = sig(pre[0]), fg = sig(pre[1]), gg = std::tanh(pre[2]), og = sig(pre[3]);
      cn[j] = fg * cs[j] + ig * gg;
      hn[j] = og * std::tanh(cn[j]);
    }
    hs = hn;
    cs = cn;
  }
  return hs;
}

TEST(Lstm, MatchesHandWrittenReference) {
  for (const auto& [in, h, steps] :
       std::vector<std::tuple<int, int, int>>{{1, 1, 1}, {3, 4, 5}, {17, 8, 9}, {40, 20, 3}}) {
    const LstmWeights w = RandomWeights(in, h, 5 + in);
    const Lstm lstm(w);
    EXPECT_EQ(lstm.input_size(), in);
    EXPECT_EQ(lstm.hidden_size(), h);
    std::mt19937_64 rng(9);
    std::normal_distribution<double> n;
    const Eigen::MatrixXd seq = Eigen::MatrixXd::NullaryExpr(steps, in, [&] { return n(rng); });
    const Eigen::VectorXd ref = ReferenceLstm(w, seq.cast<float>().cast<double>());
    auto ws = lstm.MakeWorkspace();
    const Eigen::VectorXf out = lstm.Forward(seq.cast<float>(), &ws);
    for (int j = 0; j < h; ++j)
      EXPECT_NEAR(out[j], ref[j], 2e-5) << in << " " << h << " unit " << j;
    // Step by step, and with a precomputed scaled projection, give the same state.
    lstm.Reset(&ws);
    for (int k = 0; k < steps; ++k) lstm.Step(seq.row(k).transpose().cast<float>(), &ws);
    EXPECT_TRUE(ws.h.isApprox(out, 1e-6f));
    lstm.Reset(&ws);
    for (int k = 0; k < steps; ++k) {
      const Eigen::VectorXf u = w.weight_ih * seq.row(k).transpose().cast<float>() / 2.0f;
      lstm.StepProjected(u, 2.0f, &ws);
    }
    for (int j = 0; j < h; ++j) EXPECT_NEAR(ws.h[j], ref[j], 2e-5);
  }
}

TEST(Lstm, SaturatesWithoutNaN) {
  LstmWeights w = RandomWeights(2, 3, 1);
  w.weight_ih *= 1e4f;
  const Lstm lstm(w);
  auto ws = lstm.MakeWorkspace();
  Eigen::MatrixXf seq(4, 2);
  seq << 100, -100, 1e3f, 1e3f, -1e3f, 0, 0, 0;
  const Eigen::VectorXf h = lstm.Forward(seq, &ws);
  EXPECT_TRUE(h.allFinite());
  EXPECT_LE(h.cwiseAbs().maxCoeff(), 1.0f);
}

TEST(Lstm, RejectsBadShapesAndLoadsPyTorchNames) {
  LstmWeights w = RandomWeights(3, 4, 2);
  LstmWeights bad = w;
  bad.weight_hh.resize(15, 4);
  testing::ExpectErrorContains([&] { Lstm{bad}; }, {"weight_hh", "4H x H"});
  bad = w;
  bad.bias_ih.resize(3);
  testing::ExpectErrorContains([&] { Lstm{bad}; }, {"biases"});
  bad = w;
  bad.weight_ih(0, 0) = NAN;
  testing::ExpectErrorContains([&] { Lstm{bad}; }, {"non-finite"});

  testing::TempDir dir;
  const std::string path = dir.File("lstm.h5");
  {
    h5::File f = h5::File::Create(path);
    f.WriteMatrix("/l/weight_ih_l0", w.weight_ih);
    f.WriteMatrix("/l/weight_hh_l0", w.weight_hh);
    f.WriteMatrix("/l/bias_ih_l0", Eigen::MatrixXf(w.bias_ih));
    f.WriteMatrix("/l/bias_hh_l0", Eigen::MatrixXf(w.bias_hh));
    f.WriteMatrix("/m/weight_ih_l0", w.weight_ih);
    f.WriteMatrix("/m/weight_hh_l0", w.weight_hh);
    f.WriteMatrix("/m/bias_ih_l0", Eigen::MatrixXf(w.bias_ih.head(8)));
    f.WriteMatrix("/m/bias_hh_l0", Eigen::MatrixXf(w.bias_hh));
  }
  const h5::File f = h5::File::Open(path);
  const Lstm loaded = Lstm::Load(f, "/l/");
  EXPECT_TRUE(loaded.weights().weight_ih.isApprox(w.weight_ih));
  EXPECT_TRUE(loaded.weights().bias_hh.isApprox(w.bias_hh));
  testing::ExpectErrorContains([&] { Lstm::Load(f, "/m/"); }, {"lstm.h5", "bias_ih_l0"});
}

}  // namespace
}  // namespace foresight
