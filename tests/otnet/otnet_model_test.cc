// The OTNet engine (thesis ch 6) against independent computations: the network head by hand from
// the raw MLP output; position marginals against K Var K' built explicitly and against Monte Carlo
// of hand-sampled weights (Normal and Laplace); start conditioning against the thesis's Schur
// complement of the joint Gaussian of positions at [0, taus], against a direct Bayes computation of
// the component weights, and by Monte Carlo of the engine's samples; sampling with rejection on a
// walled map against the same draws without rejection; the collision check against the exact
// segment-cell geometry and a dense brute-force walk; the artifact round trip and its corruptions.

#include "inference/otnet/otnet_model.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "inference/engine/artifact.h"
#include "tests/test_util.h"

namespace foresight::otnet {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::MatricesNear;

constexpr int kSide = 40;
constexpr int kBasis = 6;       // M
constexpr int kComponents = 3;  // Q
constexpr double kGamma = 20.0;

/// A 40 x 40 room: occupied border and a variant-dependent block (every variant has edge cells).
BinaryGrid Room(int variant) {
  BinaryGrid g(kSide, kSide);
  for (int r = 0; r < kSide; ++r)
    for (int c = 0; c < kSide; ++c)
      g.at(r, c) = (r == 0 || c == 0 || r == kSide - 1 || c == kSide - 1) ? 1 : 0;
  const int r0 = 5 + 7 * variant, c0 = 30 - 6 * variant;
  for (int r = r0; r < r0 + 4 + variant; ++r)
    for (int c = c0; c < c0 + 3 + 2 * variant; ++c) g.at(r, c) = 1;
  return g;
}

std::vector<BinaryGrid> Database() { return {Room(0), Room(1), Room(2), Room(3)}; }

/// A 2-layer MLP with N(0, scale^2) weights and biases.
Mlp RandomMlp(int in, int hidden, int out, std::uint64_t seed, float scale = 0.5f) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> n01;
  auto layer = [&](int rows, int cols) {
    DenseLayer l;
    l.weight = Eigen::MatrixXf(rows, cols);
    l.bias = Eigen::VectorXf(rows);
    for (Eigen::Index i = 0; i < l.weight.size(); ++i) l.weight.data()[i] = scale * n01(rng);
    for (Eigen::Index i = 0; i < l.bias.size(); ++i) l.bias[i] = scale * n01(rng);
    return l;
  };
  return Mlp({layer(hidden, in), layer(out, hidden)});
}

OtnetModel SmallModel(MixtureFamily family, std::uint64_t seed = 7) {
  const OtnetHead head{kComponents, 2 * kBasis};
  return OtnetModel(MapEncoder(Database(), 50.0), TrajectoryBasis(kBasis, kGamma, 1e-3),
                    RandomMlp(4, 16, head.Total(), seed), family, kComponents);
}

/// A mixture by hand: component q follows a straight line (fitted weights) with scales `spread`.
Mixture LineMixture(const TrajectoryBasis& basis, MixtureFamily family,
                    const std::vector<Eigen::Vector4d>& lines, const std::vector<double>& alpha,
                    double spread) {
  const int q_count = static_cast<int>(lines.size());
  Mixture m;
  m.family = family;
  m.alpha = Eigen::Map<const Eigen::VectorXd>(alpha.data(), q_count);
  m.mean.resize(q_count, basis.weights());
  m.scale.resize(q_count, basis.weights());
  m.gain = Eigen::MatrixXd::Zero(q_count, basis.weights());
  for (int q = 0; q < q_count; ++q) {
    Eigen::MatrixX2d waypoints(20, 2);
    for (int i = 0; i < 20; ++i) {
      const double t = i / 19.0;
      waypoints.row(i) << lines[q][0] + t * (lines[q][2] - lines[q][0]),
          lines[q][1] + t * (lines[q][3] - lines[q][1]);
    }
    m.mean.row(q) = basis.Fit(waypoints).transpose();
    for (int j = 0; j < basis.weights(); ++j) m.scale(q, j) = spread * (1.0 + 0.1 * (j % 4));
  }
  return m;
}

/// A mixture with random means and scales (any positions; for formula checks).
Mixture RandomMixture(MixtureFamily family, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> u(0.2, 1.5);
  Mixture m;
  m.family = family;
  m.alpha = Eigen::VectorXd(kComponents);
  for (auto& a : m.alpha) a = u(rng);
  m.alpha /= m.alpha.sum();
  m.mean.resize(kComponents, 2 * kBasis);
  m.scale.resize(kComponents, 2 * kBasis);
  m.gain = Eigen::MatrixXd::Zero(kComponents, 2 * kBasis);
  for (Eigen::Index i = 0; i < m.mean.size(); ++i) {
    m.mean.data()[i] = 20 + 3 * n01(rng);
    m.scale.data()[i] = u(rng);
  }
  return m;
}

/// Var = s^2 (Normal) or 2 s^2 (Laplace), built independently of the engine.
Eigen::MatrixXd VarianceDiag(const Mixture& m, int q, int d) {
  const double factor = m.family == MixtureFamily::kLaplace ? 2.0 : 1.0;
  Eigen::MatrixXd v = Eigen::MatrixXd::Zero(kBasis, kBasis);
  for (int j = 0; j < kBasis; ++j) v(j, j) = factor * std::pow(m.scale(q, d * kBasis + j), 2);
  return v;
}

/// Standard Laplace by the inverse CDF (the engine uses a signed exponential instead).
double LaplaceInverseCdf(double u) { return u < 0.5 ? std::log(2 * u) : -std::log(2 * (1 - u)); }

// ---------------------------------------------------------------------------------------------
// Head and prediction.

TEST(OtnetHead, LayoutIsComponentMajor) {
  const OtnetHead h{3, 12};
  EXPECT_EQ(h.Total(), 3 * 25);
  EXPECT_EQ(h.MeanOffset(0), 3);
  EXPECT_EQ(h.MeanOffset(2), 3 + 24);
  EXPECT_EQ(h.LogScaleOffset(0), 3 + 36);
  EXPECT_EQ(h.LogScaleOffset(2) + 12, h.Total());
}

TEST(OtnetModel, HeadMatchesAHandComputationFromTheRawOutput) {
  const OtnetHead head{kComponents, 2 * kBasis};
  Mlp raw = RandomMlp(4, 16, head.Total(), 11);
  std::vector<DenseLayer> layers = raw.layers();
  // Push a few log-scales beyond the clamp and one logit far out (a naive softmax overflows).
  layers[1].bias[head.LogScaleOffset(0) + 1] = 40.0f;
  layers[1].bias[head.LogScaleOffset(2) + 5] = -40.0f;
  for (const float logit : {0.0f, 900.0f}) {
    layers[1].bias[head.LogitOffset() + 1] = logit;
    const Mlp mlp(layers);
    const OtnetModel model(MapEncoder(Database(), 50.0), TrajectoryBasis(kBasis, kGamma, 1e-3), mlp,
                           MixtureFamily::kNormal, kComponents);
    OtnetModel::Workspace ws = model.MakeWorkspace(4, 10);
    const Eigen::VectorXd phi = Eigen::VectorXd::LinSpaced(4, 0.1, 0.9);
    Mixture m;
    model.PredictFromFeatures(phi, &ws, &m);
    // The raw network output, evaluated by the test with its own workspace.
    Mlp::Workspace mws = mlp.MakeWorkspace();
    const Eigen::VectorXf phi_f = phi.cast<float>();
    const Eigen::VectorXd y = mlp.Forward(phi_f, &mws).cast<double>();
    ASSERT_EQ(y.size(), head.Total());
    long double total = 0;
    for (int q = 0; q < kComponents; ++q) total += std::exp(static_cast<long double>(y[q]));
    for (int q = 0; q < kComponents; ++q) {
      const double expected = static_cast<double>(std::exp(static_cast<long double>(y[q])) / total);
      EXPECT_NEAR(m.alpha[q], expected, 1e-12) << "q " << q << " logit " << logit;
      for (int j = 0; j < 2 * kBasis; ++j) {
        EXPECT_EQ(m.mean(q, j), y[head.MeanOffset(q) + j]);
        const double z = y[head.LogScaleOffset(q) + j];
        const double clamped = z < -7 ? -7 : (z > 7 ? 7 : z);
        EXPECT_NEAR(m.scale(q, j), std::exp(clamped), 1e-12 * std::exp(clamped));
      }
    }
    EXPECT_TRUE(m.alpha.allFinite());
    EXPECT_NEAR(m.alpha.sum(), 1.0, 1e-15);
    EXPECT_EQ(m.scale(0, 1), std::exp(7.0));
    EXPECT_EQ(m.scale(2, 5), std::exp(-7.0));
    EXPECT_FALSE(m.conditioned);
    EXPECT_EQ(m.family, MixtureFamily::kNormal);
  }
}

TEST(OtnetModel, PredictIsEncodeThenNetwork) {
  const OtnetModel model = SmallModel(MixtureFamily::kLaplace);
  OtnetModel::Workspace ws = model.MakeWorkspace(4, 10);
  const BinaryGrid map = Room(2);
  const Mixture predicted = model.Predict(map, &ws);
  EXPECT_EQ(predicted.family, MixtureFamily::kLaplace);
  // phi by hand from the brute-force Hausdorff distances to each database map.
  const std::vector<Eigen::Vector2i> edges = EdgeCells(map);
  Eigen::VectorXd phi(4);
  for (int m = 0; m < 4; ++m) {
    const double d = AveragedHausdorffBruteForce(edges, EdgeCells(Database()[m]));
    phi[m] = std::exp(-d * d / (2 * 50.0));
  }
  Mixture direct;
  model.PredictFromFeatures(phi, &ws, &direct);
  EXPECT_TRUE(MatricesNear(predicted.alpha, direct.alpha, 1e-6));
  EXPECT_TRUE(MatricesNear(predicted.mean, direct.mean, 1e-5));
  EXPECT_TRUE(MatricesNear(predicted.scale, direct.scale, 1e-5));
  // The identical map in the database is at distance 0.
  EXPECT_EQ(ws.phi[2], 1.0);
}

TEST(OtnetModel, ConstructionChecksSizes) {
  const OtnetHead head{kComponents, 2 * kBasis};
  ExpectErrorContains(
      [&] {
        OtnetModel(MapEncoder(Database(), 50.0), TrajectoryBasis(kBasis, kGamma, 0),
                   RandomMlp(5, 8, head.Total(), 1), MixtureFamily::kNormal, kComponents);
      },
      {"takes 5 inputs", "4 maps"});
  ExpectErrorContains(
      [&] {
        OtnetModel(MapEncoder(Database(), 50.0), TrajectoryBasis(kBasis, kGamma, 0),
                   RandomMlp(4, 8, head.Total() - 1, 1), MixtureFamily::kNormal, kComponents);
      },
      {"gives 74 outputs", "needs 75"});
  ExpectErrorContains(
      [&] {
        OtnetModel(MapEncoder(Database(), 50.0), TrajectoryBasis(kBasis, kGamma, 0), Mlp(),
                   MixtureFamily::kNormal, kComponents);
      },
      {"no layers"});
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  ExpectErrorContains([&] { model.MakeWorkspace(0, 10); }, {"max_count 0"});
  ExpectErrorContains([&] { model.MakeWorkspace(3, 1); }, {"points 1"});
  OtnetModel::Workspace ws = model.MakeWorkspace(3, 10);
  Mixture m;
  ExpectErrorContains([&] { model.PredictFromFeatures(Eigen::VectorXd::Ones(3), &ws, &m); },
                      {"phi has 3", "4"});
  ExpectErrorContains(
      [&] { model.PredictFromFeatures(Eigen::VectorXd::Constant(4, std::nan("")), &ws, &m); },
      {"phi is not finite"});
}

TEST(Mixture, VarianceByFamily) {
  Mixture m = RandomMixture(MixtureFamily::kNormal, 3);
  EXPECT_TRUE(MatricesNear(m.Variance(1), m.scale.row(1).transpose().array().square().matrix(), 0));
  m.family = MixtureFamily::kLaplace;
  EXPECT_TRUE(
      MatricesNear(m.Variance(1), 2 * m.scale.row(1).transpose().array().square().matrix(), 0));
  ExpectErrorContains([&] { m.Variance(3); }, {"component 3"});
  EXPECT_STREQ(ToString(MixtureFamily::kNormal), "normal");
  EXPECT_STREQ(ToString(MixtureFamily::kLaplace), "laplace");
}

// ---------------------------------------------------------------------------------------------
// Marginals.

TEST(OtnetModel, MarginalsAreKVarKTransposed) {
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = SmallModel(family);
    const Mixture m = RandomMixture(family, 5);
    const Eigen::VectorXd taus = (Eigen::VectorXd(5) << 0.0, 0.13, 0.5, 0.77, 1.0).finished();
    const Eigen::MatrixXd k = model.basis().Design(taus);
    for (int q = 0; q < kComponents; ++q) {
      Eigen::MatrixX2d mean;
      Eigen::MatrixXd cx, cy;
      model.ComponentMarginals(m, q, taus, &mean, &cx, &cy);
      EXPECT_TRUE(MatricesNear(mean.col(0), k * m.mean.row(q).head(kBasis).transpose(), 1e-12));
      EXPECT_TRUE(MatricesNear(mean.col(1), k * m.mean.row(q).tail(kBasis).transpose(), 1e-12));
      EXPECT_TRUE(MatricesNear(cx, k * VarianceDiag(m, q, 0) * k.transpose(), 1e-12));
      EXPECT_TRUE(MatricesNear(cy, k * VarianceDiag(m, q, 1) * k.transpose(), 1e-12));
    }
  }
}

TEST(OtnetModel, MarginalsMatchMonteCarloOfWeights) {
  // N hand-sampled weight vectors of one component; positions K w. Tolerances: 5 standard errors,
  // with the standard error of each covariance entry estimated from the samples themselves.
  constexpr int kSamples = 40000;
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = SmallModel(family);
    const Mixture m = RandomMixture(family, 9);
    const Eigen::VectorXd taus = (Eigen::VectorXd(4) << 0.05, 0.4, 0.6, 0.95).finished();
    const Eigen::MatrixXd k = model.basis().Design(taus);
    const int q = 1;
    std::mt19937_64 rng(12);
    std::normal_distribution<double> n01;
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    Eigen::MatrixXd xs(kSamples, 4);
    for (int n = 0; n < kSamples; ++n) {
      Eigen::VectorXd w(kBasis);
      for (int j = 0; j < kBasis; ++j) {
        double u = u01(rng);
        while (u == 0.0) u = u01(rng);
        const double eps = family == MixtureFamily::kLaplace ? LaplaceInverseCdf(u) : n01(rng);
        w[j] = m.mean(q, j) + m.scale(q, j) * eps;
      }
      xs.row(n) = (k * w).transpose();
    }
    Eigen::MatrixX2d mean;
    Eigen::MatrixXd cx, cy;
    model.ComponentMarginals(m, q, taus, &mean, &cx, &cy);
    const Eigen::RowVectorXd mc_mean = xs.colwise().mean();
    const Eigen::MatrixXd centred = xs.rowwise() - mc_mean;
    const Eigen::MatrixXd mc_cov = centred.transpose() * centred / (kSamples - 1);
    for (int a = 0; a < 4; ++a) {
      EXPECT_NEAR(mc_mean[a], mean(a, 0), 5 * std::sqrt(cx(a, a) / kSamples));
      for (int b = 0; b < 4; ++b) {
        const Eigen::ArrayXd prod = centred.col(a).array() * centred.col(b).array();
        const double se = std::sqrt((prod - prod.mean()).square().mean() / kSamples);
        EXPECT_NEAR(mc_cov(a, b), cx(a, b), 5 * se) << ToString(family) << " " << a << "," << b;
      }
    }
  }
}

// The thesis's conditional of positions: the joint Gaussian at [0, taus] (K Var K', built here),
// conditioned on z(0) = s by the Schur complement.
void ThesisConditional(const Eigen::MatrixXd& k_full, const Eigen::VectorXd& mu_w,
                       const Eigen::MatrixXd& var_w, double s, Eigen::VectorXd* mean,
                       Eigen::MatrixXd* cov) {
  const Eigen::VectorXd mu = k_full * mu_w;
  const Eigen::MatrixXd sigma = k_full * var_w * k_full.transpose();
  const Eigen::Index l = sigma.rows() - 1;
  const Eigen::VectorXd s12 = sigma.block(1, 0, l, 1);
  *mean = mu.tail(l) + s12 / sigma(0, 0) * (s - mu[0]);
  *cov = sigma.bottomRightCorner(l, l) - s12 * s12.transpose() / sigma(0, 0);
}

TEST(OtnetModel, ConditionedMarginalsAreTheThesisSchurComplement) {
  // Filled in place: GCC 12 warns (-Wmaybe-uninitialized) on a copied .finished().
  Eigen::VectorXd taus(6);
  taus << 0.1, 0.25, 0.5, 0.6, 0.9, 1.0;
  Eigen::VectorXd taus_full(7);
  taus_full << 0.0, taus;
  const Eigen::Vector2d start(17.3, 22.9);
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = SmallModel(family);
    const Mixture prior = RandomMixture(family, 21);
    const Eigen::MatrixXd k_full = model.basis().Design(taus_full);
    Mixture cond;
    model.ConditionOnStart(prior, start, ComponentSelection::kAll, &cond);
    EXPECT_TRUE(cond.conditioned);
    EXPECT_EQ(cond.start, start);
    EXPECT_TRUE(MatricesNear(cond.scale, prior.scale, 0));
    for (int q = 0; q < kComponents; ++q) {
      Eigen::MatrixX2d mean;
      Eigen::MatrixXd cx, cy;
      model.ComponentMarginals(cond, q, taus, &mean, &cx, &cy);
      for (int d = 0; d < 2; ++d) {
        Eigen::VectorXd thesis_mean;
        Eigen::MatrixXd thesis_cov;
        const Eigen::VectorXd mu_w = prior.mean.row(q).segment(d * kBasis, kBasis).transpose();
        ThesisConditional(k_full, mu_w, VarianceDiag(prior, q, d), start[d], &thesis_mean,
                          &thesis_cov);
        EXPECT_TRUE(MatricesNear(mean.col(d), thesis_mean, 1e-9)) << ToString(family) << q << d;
        EXPECT_TRUE(MatricesNear(d == 0 ? cx : cy, thesis_cov, 1e-9)) << ToString(family) << q;
      }
      // At tau = 0 the conditioned position is the start, with no variance.
      Eigen::MatrixX2d m0;
      Eigen::MatrixXd c0x, c0y;
      model.ComponentMarginals(cond, q, Eigen::VectorXd::Zero(1), &m0, &c0x, &c0y);
      EXPECT_NEAR(m0(0, 0), start.x(), 1e-9);
      EXPECT_NEAR(m0(0, 1), start.y(), 1e-9);
      EXPECT_NEAR(c0x(0, 0), 0.0, 1e-9);
      EXPECT_NEAR(c0y(0, 0), 0.0, 1e-9);
    }
  }
}

TEST(OtnetModel, ComponentWeightsAreBayesOnTheStart) {
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    Mixture prior = RandomMixture(family, 31);
    prior.scale *= 3;  // wide enough that every component's likelihood is far from underflow
    const Eigen::MatrixXd k0 = model.basis().Design(Eigen::VectorXd::Zero(1));  // [1 x M]
    const Eigen::Vector2d start(19.0, 21.5);
    Eigen::VectorXd posterior(kComponents);
    for (int q = 0; q < kComponents; ++q) {
      double like = prior.alpha[q];
      for (int d = 0; d < 2; ++d) {
        const double mu = (k0 * prior.mean.row(q).segment(d * kBasis, kBasis).transpose())(0);
        const double var = (k0 * VarianceDiag(prior, q, d) * k0.transpose())(0, 0);
        like *= std::exp(-0.5 * std::pow(start[d] - mu, 2) / var) / std::sqrt(2 * M_PI * var);
      }
      posterior[q] = like;
    }
    ASSERT_GT(posterior.minCoeff(), 1e-200);
    posterior /= posterior.sum();
    Mixture all, nearest;
    model.ConditionOnStart(prior, start, ComponentSelection::kAll, &all);
    model.ConditionOnStart(prior, start, ComponentSelection::kNearest, &nearest);
    EXPECT_TRUE(MatricesNear(all.alpha, posterior, 1e-12)) << ToString(family);
    Eigen::Index best = 0;
    posterior.maxCoeff(&best);
    EXPECT_TRUE(MatricesNear(nearest.alpha, Eigen::VectorXd::Unit(kComponents, best), 0));
    // Both keep every component's conditioned mean.
    EXPECT_TRUE(MatricesNear(all.mean, nearest.mean, 0));
    EXPECT_TRUE(MatricesNear(all.gain, nearest.gain, 0));
  }
  // A start far from everything still conditions (log space): the nearest component takes it all.
  Mixture prior = RandomMixture(MixtureFamily::kNormal, 31);
  Mixture far;
  model.ConditionOnStart(prior, Eigen::Vector2d(1e4, -1e4), ComponentSelection::kAll, &far);
  EXPECT_TRUE(far.alpha.allFinite());
  EXPECT_NEAR(far.alpha.sum(), 1.0, 1e-12);
}

TEST(OtnetModel, ConditionOnStartErrors) {
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  const Mixture prior = RandomMixture(MixtureFamily::kNormal, 1);
  Mixture cond;
  ExpectErrorContains(
      [&] {
        model.ConditionOnStart(prior, Eigen::Vector2d(std::nan(""), 1), ComponentSelection::kAll,
                               &cond);
      },
      {"start", "not finite"});
  model.ConditionOnStart(prior, Eigen::Vector2d(3, 4), ComponentSelection::kAll, &cond);
  Mixture twice;
  ExpectErrorContains(
      [&] {
        model.ConditionOnStart(cond, Eigen::Vector2d(3, 4), ComponentSelection::kAll, &twice);
      },
      {"already conditioned", "(3, 4)"});
  Mixture bad = prior;
  bad.scale(0, 0) = -1;
  ExpectErrorContains(
      [&] { model.ConditionOnStart(bad, Eigen::Vector2d(3, 4), ComponentSelection::kAll, &cond); },
      {"scales", "-1"});
  bad = prior;
  bad.alpha[0] += 0.5;
  ExpectErrorContains(
      [&] { model.ConditionOnStart(bad, Eigen::Vector2d(3, 4), ComponentSelection::kAll, &cond); },
      {"sum to 1"});
  bad = RandomMixture(MixtureFamily::kNormal, 1);
  bad.mean.conservativeResize(kComponents, 2 * kBasis - 1);
  ExpectErrorContains(
      [&] { model.ConditionOnStart(bad, Eigen::Vector2d(3, 4), ComponentSelection::kAll, &cond); },
      {"means 3x11", "12 weights"});
}

TEST(OtnetModel, DensityIsTheDiagonalOfTheMarginals) {
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  const Mixture prior = RandomMixture(MixtureFamily::kNormal, 41);
  Mixture nearest;
  model.ConditionOnStart(prior, Eigen::Vector2d(20, 20), ComponentSelection::kNearest, &nearest);
  const Eigen::VectorXd taus = UniformTaus(9);
  for (const Mixture* m : std::vector<const Mixture*>{&prior, &nearest}) {
    const PerTimeDensity density = model.Density(*m, taus);
    std::vector<int> kept;
    for (int q = 0; q < kComponents; ++q)
      if (m->alpha[q] > 0) kept.push_back(q);
    ASSERT_EQ(density.weights.size(), static_cast<Eigen::Index>(kept.size()));
    ASSERT_EQ(density.times(), 9);
    for (std::size_t i = 0; i < kept.size(); ++i) {
      EXPECT_NEAR(density.weights[static_cast<Eigen::Index>(i)], m->alpha[kept[i]], 1e-15);
      Eigen::MatrixX2d mean;
      Eigen::MatrixXd cx, cy;
      model.ComponentMarginals(*m, kept[i], taus, &mean, &cx, &cy);
      EXPECT_TRUE(MatricesNear(density.means[i], mean, 1e-12));
      EXPECT_TRUE(MatricesNear(density.covs[i].col(0), cx.diagonal().cwiseMax(0), 1e-12));
      EXPECT_TRUE(MatricesNear(density.covs[i].col(1), Eigen::VectorXd::Zero(9), 0));
      EXPECT_TRUE(MatricesNear(density.covs[i].col(2), cy.diagonal().cwiseMax(0), 1e-12));
      EXPECT_GE(density.covs[i].minCoeff(), 0.0);
    }
  }
  EXPECT_EQ(model.Density(nearest, taus).weights.size(), 1);
}

// ---------------------------------------------------------------------------------------------
// Sampling.

BinaryGrid FreeMap() { return BinaryGrid(kSide, kSide); }

TEST(OtnetModel, ConditionedSamplesStartAtTheStart) {
  const Eigen::Vector2d start(12.25, 17.75);
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = SmallModel(family);
    const Mixture prior =
        LineMixture(model.basis(), family, {{10, 18, 30, 18}, {13, 15, 13, 35}, {11, 19, 30, 30}},
                    {0.5, 0.3, 0.2}, 0.8);
    Mixture cond;
    model.ConditionOnStart(prior, start, ComponentSelection::kAll, &cond);
    OtnetModel::Workspace ws = model.MakeWorkspace(200, 30);
    GenerateOptions options;
    options.count = 200;
    options.points = 30;
    options.max_attempts = 200;
    options.reject_collisions = false;
    std::mt19937_64 rng(5);
    const GenerateStats stats = model.Generate(FreeMap(), cond, options, &rng, &ws);
    EXPECT_EQ(stats.accepted, 200);
    EXPECT_EQ(stats.attempts, 200);
    EXPECT_EQ(stats.rejected, 0);
    double spread = 0;
    for (int k = 0; k < 200; ++k) {
      ASSERT_EQ(ws.generated[k].rows(), 30);
      EXPECT_NEAR(ws.generated[k](0, 0), start.x(), 1e-9);
      EXPECT_NEAR(ws.generated[k](0, 1), start.y(), 1e-9);
      spread += (ws.generated[k].row(29) - ws.generated[0].row(29)).norm();
    }
    EXPECT_GT(spread, 1.0);  // the ends still vary
  }
}

TEST(OtnetModel, SamplesAreTheBasisImageOfTheWeights) {
  // Unconditioned, one component with tiny scales: every sample is the mean trajectory.
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  Mixture m = LineMixture(model.basis(), MixtureFamily::kNormal, {{5, 5, 30, 20}}, {1.0}, 1e-12);
  m.alpha = Eigen::VectorXd::Unit(kComponents, 1);
  m.mean = m.mean.replicate(kComponents, 1).eval();
  m.scale = m.scale.replicate(kComponents, 1).eval();
  m.gain = Eigen::MatrixXd::Zero(kComponents, 2 * kBasis);
  m.mean.row(0).setConstant(100);  // never drawn (alpha 0)
  OtnetModel::Workspace ws = model.MakeWorkspace(5, 17);
  GenerateOptions options;
  options.count = 5;
  options.points = 17;
  std::mt19937_64 rng(1);
  const GenerateStats stats = model.Generate(FreeMap(), m, options, &rng, &ws);
  ASSERT_EQ(stats.accepted, 5);
  const Eigen::MatrixX2d expected =
      model.basis().Evaluate(m.mean.row(1).transpose(), UniformTaus(17));
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(MatricesNear(ws.generated[k], expected, 1e-9));
}

TEST(OtnetModel, ConditionedSampleMomentsMatchTheConditionalByMonteCarlo) {
  // One component kept (kNearest): the samples' positions at taus 1..5 have the conditioned mean
  // and covariance (exact for Normal; the moment-matched Laplace correction has the same moments).
  // Tolerance: 5 standard errors, those of the covariance entries estimated from the samples.
  constexpr int kSamples = 20000;
  constexpr int kPoints = 6;
  const Eigen::Vector2d start(12.5, 18.25);
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = SmallModel(family);
    const Mixture prior =
        LineMixture(model.basis(), family, {{30, 30, 5, 5}, {13, 17, 35, 20}, {5, 35, 35, 35}},
                    {0.3, 0.4, 0.3}, 0.7);
    Mixture cond;
    model.ConditionOnStart(prior, start, ComponentSelection::kNearest, &cond);
    ASSERT_EQ(cond.alpha[1], 1.0);
    OtnetModel::Workspace ws = model.MakeWorkspace(kSamples, kPoints);
    GenerateOptions options;
    options.count = kSamples;
    options.points = kPoints;
    options.max_attempts = kSamples;
    options.reject_collisions = false;
    std::mt19937_64 rng(77);
    ASSERT_EQ(model.Generate(FreeMap(), cond, options, &rng, &ws).accepted, kSamples);
    const Eigen::VectorXd taus = UniformTaus(kPoints).tail(kPoints - 1);
    Eigen::MatrixX2d mean;
    Eigen::MatrixXd cx, cy;
    model.ComponentMarginals(cond, 1, taus, &mean, &cx, &cy);
    for (int d = 0; d < 2; ++d) {
      Eigen::MatrixXd xs(kSamples, kPoints - 1);
      for (int n = 0; n < kSamples; ++n)
        xs.row(n) = ws.generated[n].col(d).tail(kPoints - 1).transpose();
      const Eigen::RowVectorXd mc_mean = xs.colwise().mean();
      const Eigen::MatrixXd centred = xs.rowwise() - mc_mean;
      const Eigen::MatrixXd mc_cov = centred.transpose() * centred / (kSamples - 1);
      const Eigen::MatrixXd& cov = d == 0 ? cx : cy;
      for (int a = 0; a < kPoints - 1; ++a) {
        EXPECT_NEAR(mc_mean[a], mean(a, d), 5 * std::sqrt(cov(a, a) / kSamples));
        for (int b = 0; b < kPoints - 1; ++b) {
          const Eigen::ArrayXd prod = centred.col(a).array() * centred.col(b).array();
          const double se = std::sqrt((prod - prod.mean()).square().mean() / kSamples);
          EXPECT_NEAR(mc_cov(a, b), cov(a, b), 5 * se) << ToString(family) << d << a << b;
        }
      }
    }
  }
}

TEST(OtnetModel, SampledWeightsFollowTheFamilyDistribution) {
  // Only w_x[0] varies (scale 1.5, the rest 1e-12) and k_0(0) = 1 (centre 0), so
  // (x(0) - mu_x(0)) / 1.5 is the engine's eps: a Kolmogorov-Smirnov test against the standard
  // Normal / Laplace CDF (critical value 1.95 / sqrt(N) at the 0.1 % level).
  constexpr int kSamples = 20000;
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = SmallModel(family);
    Mixture m = RandomMixture(family, 4);
    m.scale.setConstant(1e-12);
    m.scale.col(0).setConstant(1.5);
    OtnetModel::Workspace ws = model.MakeWorkspace(kSamples, 2);
    GenerateOptions options;
    options.count = kSamples;
    options.points = 2;
    options.max_attempts = kSamples;
    options.reject_collisions = false;
    std::mt19937_64 rng(6);
    ASSERT_EQ(model.Generate(FreeMap(), m, options, &rng, &ws).accepted, kSamples);
    const Eigen::MatrixXd k0 = model.basis().Design(Eigen::VectorXd::Zero(1));
    ASSERT_EQ(k0(0, 0), 1.0);
    // y carries no noise (1e-11), so y(0) names each sample's component; then eps follows.
    std::vector<double> eps;
    for (int n = 0; n < kSamples; ++n) {
      double best = std::numeric_limits<double>::infinity();
      for (int q = 0; q < kComponents; ++q) {
        const double mu_y = (k0 * m.mean.row(q).tail(kBasis).transpose())(0);
        const double off = std::abs(ws.generated[n](0, 1) - mu_y);
        if (off < 1e-6)
          best = (ws.generated[n](0, 0) - (k0 * m.mean.row(q).head(kBasis).transpose())(0)) / 1.5;
      }
      ASSERT_TRUE(std::isfinite(best)) << n;
      eps.push_back(best);
    }
    std::sort(eps.begin(), eps.end());
    double ks = 0;
    for (int n = 0; n < kSamples; ++n) {
      const double e = eps[n];
      const double cdf = family == MixtureFamily::kLaplace
                             ? (e < 0 ? 0.5 * std::exp(e) : 1 - 0.5 * std::exp(-e))
                             : 0.5 * std::erfc(-e / std::sqrt(2.0));
      ks = std::max({ks, std::abs(cdf - static_cast<double>(n) / kSamples),
                     std::abs(cdf - static_cast<double>(n + 1) / kSamples)});
    }
    EXPECT_LT(ks, 1.95 / std::sqrt(kSamples)) << ToString(family);
  }
}

TEST(OtnetModel, ComponentsAreDrawnByAlpha) {
  // Well-separated components; each sample's end point tells its component. Frequencies within
  // 5 binomial standard errors of alpha.
  constexpr int kSamples = 6000;
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  const Mixture m =
      LineMixture(model.basis(), MixtureFamily::kNormal,
                  {{20, 20, 5, 5}, {20, 20, 35, 5}, {20, 20, 20, 35}}, {0.15, 0.0, 0.85}, 0.3);
  Mixture three = m;
  three.alpha << 0.2, 0.3, 0.5;
  for (const Mixture* mix : std::vector<const Mixture*>{&m, &three}) {
    OtnetModel::Workspace ws = model.MakeWorkspace(kSamples, 10);
    GenerateOptions options;
    options.count = kSamples;
    options.points = 10;
    options.max_attempts = kSamples;
    options.reject_collisions = false;
    std::mt19937_64 rng(8);
    ASSERT_EQ(model.Generate(FreeMap(), *mix, options, &rng, &ws).accepted, kSamples);
    Eigen::Vector3d counts = Eigen::Vector3d::Zero();
    const Eigen::Vector2d ends[3] = {{5, 5}, {35, 5}, {20, 35}};
    for (int n = 0; n < kSamples; ++n) {
      const Eigen::Vector2d end = ws.generated[n].row(9).transpose();
      int best = 0;
      for (int q = 1; q < 3; ++q)
        if ((end - ends[q]).norm() < (end - ends[best]).norm()) best = q;
      counts[best] += 1;
    }
    for (int q = 0; q < 3; ++q) {
      const double p = mix->alpha[q];
      EXPECT_NEAR(counts[q] / kSamples, p, 5 * std::sqrt(p * (1 - p) / kSamples) + 1e-12) << q;
    }
  }
}

/// A map whose middle columns 19 and 20 are a wall from top to bottom.
BinaryGrid WallMap() {
  BinaryGrid g(kSide, kSide);
  for (int r = 0; r < kSide; ++r) g.at(r, 19) = g.at(r, 20) = 1;
  return g;
}

TEST(OtnetModel, RejectionDropsExactlyTheCollidingDraws) {
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  // Component 0 stays left of the wall, component 1 crosses it, component 2 is borderline.
  const Mixture m =
      LineMixture(model.basis(), MixtureFamily::kNormal,
                  {{4, 10, 14, 30}, {5, 20, 35, 20}, {10, 5, 17.5, 35}}, {0.4, 0.4, 0.2}, 0.4);
  const BinaryGrid wall = WallMap();
  constexpr int kDraws = 400;
  OtnetModel::Workspace all_ws = model.MakeWorkspace(kDraws, 50);
  GenerateOptions options;
  options.count = kDraws;
  options.points = 50;
  options.max_attempts = kDraws;
  options.reject_collisions = false;
  std::mt19937_64 rng_all(99);
  const GenerateStats all = model.Generate(wall, m, options, &rng_all, &all_ws);
  ASSERT_EQ(all.accepted, kDraws);
  std::vector<int> free_draws;
  int crossing = 0;
  for (int k = 0; k < kDraws; ++k) {
    const bool crosses = all_ws.generated[k].col(0).maxCoeff() >= 19.0;
    crossing += crosses;
    const bool collides = TrajectoryCollides(wall, all_ws.generated[k], options.check_step);
    if (crosses) {
      EXPECT_TRUE(collides) << k;  // every crossing touches the wall
    }
    if (!collides) free_draws.push_back(k);
  }
  EXPECT_GT(crossing, kDraws / 4);
  EXPECT_GT(static_cast<int>(free_draws.size()), kDraws / 4);

  // Same seed with rejection: the accepted samples are exactly the non-colliding draws, in order.
  OtnetModel::Workspace ws = model.MakeWorkspace(kDraws, 50);
  options.reject_collisions = true;
  std::mt19937_64 rng(99);
  const GenerateStats stats = model.Generate(wall, m, options, &rng, &ws);
  EXPECT_EQ(stats.attempts, kDraws);
  EXPECT_EQ(stats.accepted, static_cast<int>(free_draws.size()));
  EXPECT_EQ(stats.rejected, kDraws - stats.accepted);
  for (int k = 0; k < stats.accepted; ++k)
    EXPECT_TRUE(MatricesNear(ws.generated[k], all_ws.generated[free_draws[k]], 0)) << k;

  // Enough attempts: stops at count; too few: stops at max_attempts.
  options.count = 100;
  options.max_attempts = 2000;
  std::mt19937_64 rng2(3);
  const GenerateStats enough = model.Generate(wall, m, options, &rng2, &ws);
  EXPECT_EQ(enough.accepted, 100);
  EXPECT_EQ(enough.accepted + enough.rejected, enough.attempts);
  EXPECT_GT(enough.rejected, 0);
  for (int k = 0; k < 100; ++k) EXPECT_LT(ws.generated[k].col(0).maxCoeff(), 19.0);
  options.max_attempts = 110;
  std::mt19937_64 rng3(3);
  const GenerateStats few = model.Generate(wall, m, options, &rng3, &ws);
  EXPECT_EQ(few.attempts, 110);
  EXPECT_LT(few.accepted, 100);
  EXPECT_EQ(few.accepted + few.rejected, few.attempts);
}

TEST(OtnetModel, GenerateIsDeterministicBySeed) {
  const OtnetModel model = SmallModel(MixtureFamily::kLaplace);
  const Mixture m =
      LineMixture(model.basis(), MixtureFamily::kLaplace,
                  {{4, 10, 14, 30}, {5, 20, 35, 20}, {10, 5, 17.5, 35}}, {0.4, 0.4, 0.2}, 0.4);
  GenerateOptions options;
  options.count = 20;
  options.points = 25;
  auto run = [&](std::uint64_t seed) {
    OtnetModel::Workspace ws = model.MakeWorkspace(20, 25);
    std::mt19937_64 rng(seed);
    const GenerateStats s = model.Generate(WallMap(), m, options, &rng, &ws);
    ws.generated.resize(static_cast<std::size_t>(s.accepted));
    return ws.generated;
  };
  const auto a = run(4), b = run(4), c = run(5);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_TRUE(MatricesNear(a[k], b[k], 0));
  EXPECT_FALSE(MatricesNear(a[0], c[0], 1e-6));
}

TEST(OtnetModel, GenerateErrors) {
  const OtnetModel model = SmallModel(MixtureFamily::kNormal);
  const Mixture prior =
      LineMixture(model.basis(), MixtureFamily::kNormal,
                  {{4, 10, 14, 30}, {5, 20, 35, 20}, {10, 5, 17.5, 35}}, {0.4, 0.4, 0.2}, 0.4);
  OtnetModel::Workspace ws = model.MakeWorkspace(10, 20);
  std::mt19937_64 rng(1);
  GenerateOptions options;
  options.count = 10;
  options.points = 20;
  const BinaryGrid wall = WallMap();
  Mixture cond;
  model.ConditionOnStart(prior, Eigen::Vector2d(19.5, 3.25), ComponentSelection::kAll, &cond);
  ExpectErrorContains([&] { model.Generate(wall, cond, options, &rng, &ws); },
                      {"(19.5, 3.25)", "occupied"});
  model.ConditionOnStart(prior, Eigen::Vector2d(-0.5, 3.0), ComponentSelection::kAll, &cond);
  ExpectErrorContains([&] { model.Generate(wall, cond, options, &rng, &ws); },
                      {"(-0.5, 3)", "outside"});
  model.ConditionOnStart(prior, Eigen::Vector2d(5, 20), ComponentSelection::kAll, &cond);
  EXPECT_NO_THROW(model.Generate(wall, cond, options, &rng, &ws));
  GenerateOptions o = options;
  o.count = 11;
  ExpectErrorContains([&] { model.Generate(wall, prior, o, &rng, &ws); }, {"count 11", "10"});
  o = options;
  o.points = 21;
  ExpectErrorContains([&] { model.Generate(wall, prior, o, &rng, &ws); }, {"points 21", "20"});
  o.points = 1;
  ExpectErrorContains([&] { model.Generate(wall, prior, o, &rng, &ws); }, {"points 1"});
  o = options;
  o.max_attempts = 9;
  ExpectErrorContains([&] { model.Generate(wall, prior, o, &rng, &ws); }, {"max_attempts 9"});
  o = options;
  o.check_step = 0;
  ExpectErrorContains([&] { model.Generate(wall, prior, o, &rng, &ws); }, {"check_step 0"});
  // Fewer points than the workspace holds is fine.
  o = options;
  o.points = 7;
  const GenerateStats s = model.Generate(wall, prior, o, &rng, &ws);
  ASSERT_GT(s.accepted, 0);
  EXPECT_EQ(ws.generated[0].rows(), 7);
}

// ---------------------------------------------------------------------------------------------
// Collision check.

/// The parameter interval [t0, t1] of segment p -> p + t d (t in [0, 1]) inside the box [lo, hi]
/// (slab method); false when they do not meet.
bool Clip(const Eigen::Vector2d& p, const Eigen::Vector2d& d, const Eigen::Vector2d& lo,
          const Eigen::Vector2d& hi, double* t0, double* t1) {
  *t0 = 0;
  *t1 = 1;
  for (int a = 0; a < 2; ++a) {
    if (d[a] == 0) {
      if (p[a] < lo[a] || p[a] > hi[a]) return false;
      continue;
    }
    double ta = (lo[a] - p[a]) / d[a], tb = (hi[a] - p[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    *t0 = std::max(*t0, ta);
    *t1 = std::min(*t1, tb);
  }
  return *t1 > *t0;
}

/// The longest piece of the polyline inside one occupied cell or outside the grid (exact).
double LongestBadChord(const BinaryGrid& map, const Eigen::MatrixX2d& pts) {
  double worst = 0, t0 = 0, t1 = 0;
  for (Eigen::Index i = 0; i + 1 < pts.rows(); ++i) {
    const Eigen::Vector2d p = pts.row(i).transpose(), d = (pts.row(i + 1) - pts.row(i)).transpose();
    for (int r = 0; r < map.height; ++r)
      for (int c = 0; c < map.width; ++c)
        if (map.at(r, c) &&
            Clip(p, d, Eigen::Vector2d(c, r), Eigen::Vector2d(c + 1, r + 1), &t0, &t1))
          worst = std::max(worst, (t1 - t0) * d.norm());
    // Outside the grid: the pieces before and after the part inside its box.
    if (Clip(p, d, Eigen::Vector2d(0, 0), Eigen::Vector2d(map.width, map.height), &t0, &t1))
      worst = std::max(worst, std::max(t0, 1 - t1) * d.norm());
    else
      worst = std::max(worst, d.norm());
  }
  return worst;
}

/// Dense brute force: points every 0.01 of arc length from each segment's start, and every vertex.
bool DenseCollides(const BinaryGrid& map, const Eigen::MatrixX2d& pts) {
  for (Eigen::Index i = 0; i < pts.rows(); ++i)
    if (map.OccupiedAt(pts(i, 0), pts(i, 1))) return true;
  for (Eigen::Index i = 0; i + 1 < pts.rows(); ++i) {
    const Eigen::Vector2d p = pts.row(i).transpose(), d = (pts.row(i + 1) - pts.row(i)).transpose();
    const double length = d.norm();
    for (double s = 0.01; s < length; s += 0.01) {
      const Eigen::Vector2d x = p + (s / length) * d;
      if (map.OccupiedAt(x.x(), x.y())) return true;
    }
  }
  return false;
}

TEST(TrajectoryCollides, AgreesWithExactGeometryAndDenseWalkOnRandomCases) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> coord(-1.0, 41.0), step(-6.0, 6.0);
  std::uniform_int_distribution<int> corner(0, kSide - 1), size(1, 7), n_rects(2, 6), n_pts(2, 6);
  int decisive_free = 0, decisive_hit = 0, coarse_misses = 0;
  for (int trial = 0; trial < 300; ++trial) {
    BinaryGrid map(kSide, kSide);
    for (int k = n_rects(rng); k > 0; --k) {
      const int r0 = corner(rng), c0 = corner(rng), h = size(rng), w = size(rng);
      for (int r = r0; r < std::min(kSide, r0 + h); ++r)
        for (int c = c0; c < std::min(kSide, c0 + w); ++c) map.at(r, c) = 1;
    }
    Eigen::MatrixX2d pts(n_pts(rng), 2);
    pts.row(0) << coord(rng), coord(rng);
    for (Eigen::Index i = 1; i < pts.rows(); ++i)
      pts.row(i) = pts.row(i - 1) + Eigen::RowVector2d(step(rng), step(rng));
    const double chord = LongestBadChord(map, pts);
    const bool dense = DenseCollides(map, pts);
    for (const double check : {0.25, 0.01}) {
      const bool hit = TrajectoryCollides(map, pts, check);
      if (hit) {
        EXPECT_GT(chord, 0.0) << "false positive, trial " << trial;  // points on the line
      }
      if (chord > check) {
        EXPECT_TRUE(hit) << "missed a chord of " << chord << ", trial " << trial;
      }
      if (check == 0.25) coarse_misses += dense && !hit;
      // Away from the undecidable band (a chord shorter than both spacings) they agree.
      if (check == 0.01 && (chord == 0 || chord > 0.02)) {
        EXPECT_EQ(hit, dense) << "trial " << trial << " chord " << chord;
        (chord == 0 ? decisive_free : decisive_hit) += 1;
      }
    }
  }
  EXPECT_GT(decisive_free, 40);
  EXPECT_GT(decisive_hit, 40);
  // A 0.25 step misses only chords shorter than 0.25 (checked above); how often that happens:
  RecordProperty("coarse_misses", coarse_misses);
  RecordProperty("decisive_free", decisive_free);
  RecordProperty("decisive_hit", decisive_hit);
  EXPECT_LT(coarse_misses, 15);
}

TEST(TrajectoryCollides, EdgeCases) {
  const BinaryGrid wall = WallMap();
  Eigen::MatrixX2d one(1, 2);
  one << 5, 5;
  EXPECT_FALSE(TrajectoryCollides(wall, one, 0.25));
  one << 19.5, 5;
  EXPECT_TRUE(TrajectoryCollides(wall, one, 0.25));
  one << 40.0, 5;  // x = width is outside
  EXPECT_TRUE(TrajectoryCollides(wall, one, 0.25));
  Eigen::MatrixX2d seg(2, 2);
  seg << 18.5, 5, 21.5, 5;  // both ends free, the middle in the wall
  EXPECT_TRUE(TrajectoryCollides(wall, seg, 0.25));
  EXPECT_FALSE(TrajectoryCollides(wall, seg, 10.0));  // only the endpoints checked
  seg << 1, 1, std::nan(""), 2;
  EXPECT_TRUE(TrajectoryCollides(wall, seg, 0.25));
  ExpectErrorContains([&] { TrajectoryCollides(wall, seg, 0.0); }, {"check_step 0"});
  ExpectErrorContains([&] { TrajectoryCollides(wall, Eigen::MatrixX2d(0, 2), 0.25); }, {"empty"});
}

// ---------------------------------------------------------------------------------------------
// Artifact.

void ExpectSamePredictions(const OtnetModel& a, const OtnetModel& b) {
  OtnetModel::Workspace wa = a.MakeWorkspace(4, 10), wb = b.MakeWorkspace(4, 10);
  for (int v = 0; v < 4; ++v) {
    BinaryGrid map = Room(v);
    map.at(20, 20) = 1;  // not a database map
    const Mixture ma = a.Predict(map, &wa);
    const Mixture mb = b.Predict(map, &wb);
    EXPECT_TRUE(MatricesNear(ma.alpha, mb.alpha, 0));
    EXPECT_TRUE(MatricesNear(ma.mean, mb.mean, 0));
    EXPECT_TRUE(MatricesNear(ma.scale, mb.scale, 0));
    EXPECT_EQ(ma.family, mb.family);
  }
}

TEST(OtnetArtifact, RoundTripGivesIdenticalPredictions) {
  testing::TempDir dir;
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = SmallModel(family, 17);
    const std::string path = dir.File(std::string("otnet_") + ToString(family) + ".h5");
    model.Save(path, "kind: otnet\n", 42);
    const OtnetModel loaded = OtnetModel::Load(path);
    EXPECT_EQ(loaded.family(), family);
    EXPECT_EQ(loaded.components(), kComponents);
    EXPECT_EQ(loaded.basis().size(), kBasis);
    EXPECT_EQ(loaded.basis().gamma(), kGamma);
    EXPECT_EQ(loaded.basis().ridge(), 1e-3);
    EXPECT_EQ(loaded.encoder().length_scale(), 50.0);
    ASSERT_EQ(loaded.encoder().size(), 4);
    for (int m = 0; m < 4; ++m)
      EXPECT_EQ(loaded.encoder().database()[m].cells, Database()[m].cells) << m;
    ASSERT_EQ(loaded.mlp().layers().size(), 2u);
    ExpectSamePredictions(model, loaded);
    EXPECT_EQ(Artifact::Open(path, kOtnetModelType).seed(), 42);
    EXPECT_EQ(Artifact::Open(path, kOtnetModelType).config_yaml(), "kind: otnet\n");
  }
}

// Fuzz finding (tests/fuzz/corpus/otnet_artifact/regress_huge_log_scale_offset): an offset of
// 1.8e162 loaded and the mixture scales overflowed to inf on the first query.
TEST(OtnetArtifact, HugeLogScaleOffsetIsRefused) {
  testing::TempDir dir;
  OtnetModel model = SmallModel(MixtureFamily::kNormal, 17);
  Eigen::VectorXd offset = Eigen::VectorXd::Zero(2 * kBasis);
  offset[1] = 1.76e162;
  model.SetLogScaleOffset(offset);
  const std::string path = dir.File("offset.h5");
  model.Save(path, "kind: otnet\n", 42);
  ExpectErrorContains([&] { OtnetModel::Load(path); },
                      {path, "/model/log_scale_offset[1]", "1.76e+162", "-100 to 100"});
}

// Raw HDF5 edits (independent of core/h5).
void OverwriteStringAttr(const std::string& path, const std::string& object,
                         const std::string& name, const std::string& value) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t o = H5Oopen(f, object.c_str(), H5P_DEFAULT);
  ASSERT_GE(o, 0);
  if (H5Aexists(o, name.c_str()) > 0) H5Adelete(o, name.c_str());
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size());
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(o, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(H5Awrite(a, type, value.data()), 0);
  H5Aclose(a);
  H5Sclose(space);
  H5Tclose(type);
  H5Oclose(o);
  EXPECT_GE(H5Fclose(f), 0);
}

void ReplaceIntDataset(const std::string& path, const std::string& name,
                       const std::vector<std::int64_t>& data, const std::vector<hsize_t>& shape) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  ASSERT_GE(H5Ldelete(f, name.c_str(), H5P_DEFAULT), 0) << name;
  const hid_t space = H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr);
  const hid_t ds =
      H5Dcreate2(f, name.c_str(), H5T_NATIVE_INT64, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), 0);
  H5Dclose(ds);
  H5Sclose(space);
  EXPECT_GE(H5Fclose(f), 0);
}

void RenameLink(const std::string& path, const std::string& from, const std::string& to) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  EXPECT_GE(H5Lmove(f, from.c_str(), f, to.c_str(), H5P_DEFAULT, H5P_DEFAULT), 0);
  EXPECT_GE(H5Fclose(f), 0);
}

class BadOtnet : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = dir_.File("otnet.h5");
    SmallModel(MixtureFamily::kNormal).Save(path_, "", 1);
    ASSERT_NO_THROW(OtnetModel::Load(path_));
  }
  std::vector<std::int64_t> DatabaseValues() const {
    std::vector<std::int64_t> v;
    for (const BinaryGrid& g : Database()) v.insert(v.end(), g.cells.begin(), g.cells.end());
    return v;
  }
  testing::TempDir dir_;
  std::string path_;
};

TEST_F(BadOtnet, MissingAndTruncated) {
  ExpectErrorContains([&] { OtnetModel::Load(dir_.File("none.h5")); }, {"none.h5"});
  testing::Truncate(path_, 900);
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_});
}

TEST_F(BadOtnet, WrongModelType) {
  OverwriteStringAttr(path_, "/", "model_type", "span_predictor");
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "span_predictor", "otnet"});
}

TEST_F(BadOtnet, BadFamily) {
  OverwriteStringAttr(path_, "/model", "family", "gaussian");
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "/model/family", "gaussian"});
  OverwriteStringAttr(path_, "/model", "family", "laplace");
  EXPECT_EQ(OtnetModel::Load(path_).family(), MixtureFamily::kLaplace);
}

TEST_F(BadOtnet, InconsistentSizes) {
  testing::OverwriteAttr(path_, "/model", "database_size", std::int64_t{5});
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "/model/database", "[4x40x40]"});
  testing::OverwriteAttr(path_, "/model", "database_size", std::int64_t{4});
  testing::OverwriteAttr(path_, "/model", "width", std::int64_t{41});
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "/model/database", "4x40x41"});
  testing::OverwriteAttr(path_, "/model", "width", std::int64_t{40});
  testing::OverwriteAttr(path_, "/model", "components", std::int64_t{2});
  ExpectErrorContains([&] { OtnetModel::Load(path_); },
                      {path_, "layer1", "75 outputs", "components 2", "need 50"});
  testing::OverwriteAttr(path_, "/model", "components", std::int64_t{3});
  testing::OverwriteAttr(path_, "/model", "num_basis", std::int64_t{7});
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "num_basis 7", "need 87"});
  testing::OverwriteAttr(path_, "/model", "num_basis", std::int64_t{6});
  // The database with one map fewer, consistently with the attribute: the MLP input no longer is.
  std::vector<std::int64_t> v = DatabaseValues();
  v.resize(3 * 1600);
  ReplaceIntDataset(path_, "/model/database", v, {3, 40, 40});
  testing::OverwriteAttr(path_, "/model", "database_size", std::int64_t{3});
  ExpectErrorContains([&] { OtnetModel::Load(path_); },
                      {path_, "layer0/weight takes 4 inputs", "database_size is 3"});
  ReplaceIntDataset(path_, "/model/database", DatabaseValues(), {4, 1600});
  testing::OverwriteAttr(path_, "/model", "database_size", std::int64_t{4});
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "/model/database", "[4x1600]"});
}

TEST_F(BadOtnet, DatabaseValuesMustBeZeroOrOne) {
  for (const std::int64_t bad : {std::int64_t{2}, std::int64_t{-1}, std::int64_t{256}}) {
    std::vector<std::int64_t> v = DatabaseValues();
    v[1600 + 40 * 7 + 9] = bad;  // map 1, row 7, column 9
    ReplaceIntDataset(path_, "/model/database", v, {4, 40, 40});
    ExpectErrorContains(
        [&] { OtnetModel::Load(path_); },
        {path_, "/model/database", "holds " + std::to_string(bad), "map 1, row 7, column 9"});
  }
  // Values 0/1 stored as int64 load (any integer type is accepted).
  ReplaceIntDataset(path_, "/model/database", DatabaseValues(), {4, 40, 40});
  EXPECT_NO_THROW(OtnetModel::Load(path_));
  // A database map without edge cells is refused by the encoder, the message naming the file.
  std::vector<std::int64_t> v = DatabaseValues();
  std::fill(v.begin() + 2 * 1600, v.begin() + 3 * 1600, 0);
  ReplaceIntDataset(path_, "/model/database", v, {4, 40, 40});
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "database map 2", "edge"});
}

TEST_F(BadOtnet, BadNumbers) {
  testing::OverwriteAttr(path_, "/model", "gamma", -2.0);
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "gamma", "-2"});
  testing::OverwriteAttr(path_, "/model", "gamma", kGamma);
  testing::OverwriteAttr(path_, "/model", "length_scale", std::nan(""));
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "length_scale", "nan"});
  testing::OverwriteAttr(path_, "/model", "length_scale", 0.0);
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "length_scale"});
  testing::OverwriteAttr(path_, "/model", "length_scale", 50.0);
  testing::OverwriteAttr(path_, "/model", "ridge", -1.0);
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "ridge", "-1"});
  testing::OverwriteAttr(path_, "/model", "ridge", 1e-3);
  testing::OverwriteAttr(path_, "/model", "components", std::int64_t{0});
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "components", "0"});
}

TEST_F(BadOtnet, Layers) {
  RenameLink(path_, "/weights/layer1", "/weights/head");
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "/weights/head", "layer0"});
  RenameLink(path_, "/weights/head", "/weights/layer2");
  ExpectErrorContains([&] { OtnetModel::Load(path_); }, {path_, "/weights/layer2"});
  RenameLink(path_, "/weights/layer2", "/weights/layer1");
  EXPECT_NO_THROW(OtnetModel::Load(path_));
}

}  // namespace
}  // namespace foresight::otnet
