#define FORESIGHT_ALLOC_COUNTER_MALLOC
#include "tests/alloc_counter.h"
// (own binary: the counter replaces the global allocator)

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "core/von_mises.h"
#include "models/directional/knn_directional.h"
#include "tests/test_util.h"

namespace foresight::directional {
namespace {

double Uniform(std::mt19937_64* rng, double lo, double hi) {
  return lo + (hi - lo) * std::uniform_real_distribution<double>(0, 1)(*rng);
}

DirectionalSamples RandomSamples(Eigen::Index n, std::uint64_t seed, double extent,
                                 double duration) {
  std::mt19937_64 rng(seed);
  DirectionalSamples s;
  s.x.resize(n);
  s.y.resize(n);
  s.t.resize(n);
  s.theta.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s.x[i] = Uniform(&rng, 0, extent);
    s.y[i] = Uniform(&rng, 0, extent);
    s.t[i] = Uniform(&rng, 0, duration);
    s.theta[i] = WrapAngle(Uniform(&rng, -M_PI, M_PI));
  }
  return s;
}

/// Brute force: the k training indices nearest to q, by (squared distance, index).
std::vector<Eigen::Index> BruteNeighbours(const DirectionalSamples& train, const KnnConfig& c,
                                          double x, double y, double t) {
  std::vector<std::pair<double, Eigen::Index>> all;
  for (Eigen::Index j = 0; j < train.size(); ++j) {
    const double dx = x - train.x[j], dy = y - train.y[j];
    double d2 = dx * dx + dy * dy;
    if (c.use_time) {
      const double dt = c.time_scale * t - c.time_scale * train.t[j];
      d2 += dt * dt;
    }
    all.emplace_back(d2, j);
  }
  std::sort(all.begin(), all.end());
  std::vector<Eigen::Index> out;
  for (int j = 0; j < c.k; ++j) out.push_back(all[static_cast<std::size_t>(j)].second);
  return out;
}

void ExpectMatchesBruteForce(const DirectionalSamples& train, const DirectionalSamples& query,
                             const KnnConfig& c) {
  const KnnMap map = KnnMap::Fit(train, c);
  VonMisesMixtureBatch out;
  map.Query(query.x, query.y, query.t, &out);
  ASSERT_EQ(out.alpha.rows(), query.size());
  ASSERT_EQ(out.alpha.cols(), c.k);
  for (Eigen::Index i = 0; i < query.size(); ++i) {
    const auto nn = BruteNeighbours(train, c, query.x[i], query.y[i], query.t[i]);
    EXPECT_EQ(map.Neighbours(query.x[i], query.y[i], query.t[i]), nn) << "query " << i;
    for (int j = 0; j < c.k; ++j) {
      EXPECT_EQ(out.mu(i, j), train.theta[nn[static_cast<std::size_t>(j)]])
          << "query " << i << " neighbour " << j;
      EXPECT_EQ(out.alpha(i, j), 1.0 / c.k);
      EXPECT_EQ(out.kappa(i, j), c.kappa);
    }
  }
}

TEST(KnnDirectional, MatchesBruteForceInSpaceAndSpaceTime) {
  const DirectionalSamples train = RandomSamples(1500, 1, 20.0, 100.0);
  const DirectionalSamples query = RandomSamples(200, 2, 22.0, 110.0);  // some outside
  for (const int k : {1, 3}) {
    for (const bool use_time : {false, true}) {
      KnnConfig c;
      c.k = k;
      c.kappa = 30;
      c.use_time = use_time;
      c.time_scale = 0.3;
      SCOPED_TRACE(::testing::Message() << "k " << k << " use_time " << use_time);
      ExpectMatchesBruteForce(train, query, c);
    }
  }
}

TEST(KnnDirectional, TiesGoToTheLowerTrainingIndex) {
  // Integer grid with every point twice (the copy has the higher index), queried at half-integer
  // points: many neighbours at exactly equal distances.
  DirectionalSamples train;
  const int side = 12, n = 2 * side * side;
  train.x.resize(n);
  train.y.resize(n);
  train.t.setZero(n);
  train.theta.resize(n);
  for (int i = 0; i < n; ++i) {
    const int cell = i % (side * side);
    train.x[i] = cell % side;
    train.y[i] = cell / side;
    train.theta[i] = WrapAngle(0.01 * i);
  }
  DirectionalSamples query;
  std::mt19937_64 rng(5);
  const int m = 100;
  query.x.resize(m);
  query.y.resize(m);
  query.t.setZero(m);
  for (int i = 0; i < m; ++i) {
    query.x[i] = 0.5 * static_cast<double>(rng() % (2 * side));
    query.y[i] = 0.5 * static_cast<double>(rng() % (2 * side));
  }
  for (const int k : {1, 3, 8}) {
    KnnConfig c;
    c.k = k;
    SCOPED_TRACE(::testing::Message() << "k " << k);
    ExpectMatchesBruteForce(train, query, c);
  }
  // By hand: at (0, 0) the two copies of grid point 0 are at distance 0: indices 0 and 144.
  KnnConfig c;
  c.k = 2;
  EXPECT_EQ(KnnMap::Fit(train, c).Neighbours(0, 0, 0), (std::vector<Eigen::Index>{0, side * side}));
}

TEST(KnnDirectional, TimeSelectsTheNeighbourThatWasThereThen) {
  // Two samples at the same place, headings 0 at t = 0 and pi/2 at t = 50: without time the lower
  // index wins the tie; with time the one closer in time.
  DirectionalSamples train;
  train.x = Eigen::Vector3d(1, 1, 9);
  train.y = Eigen::Vector3d(1, 1, 9);
  train.t = Eigen::Vector3d(0, 50, 25);
  train.theta = Eigen::Vector3d(0, M_PI / 2, -M_PI);
  KnnConfig c;
  VonMisesMixtureBatch out;
  const Eigen::VectorXd x = Eigen::Vector2d(1.1, 1.1), y = Eigen::Vector2d(1, 1),
                        t = Eigen::Vector2d(45, 5);
  KnnMap::Fit(train, c).Query(x, y, Eigen::VectorXd(), &out);  // t may be empty
  EXPECT_EQ(out.mu(0, 0), 0.0);
  EXPECT_EQ(out.mu(1, 0), 0.0);
  c.use_time = true;
  c.time_scale = 1.0;
  KnnMap::Fit(train, c).Query(x, y, t, &out);
  EXPECT_EQ(out.mu(0, 0), M_PI / 2);
  EXPECT_EQ(out.mu(1, 0), 0.0);
  // A tiny time scale makes time irrelevant again; a huge one makes place irrelevant: at t = 25
  // the far sample (9, 9) is nearest.
  c.time_scale = 1e-12;
  KnnMap::Fit(train, c).Query(x, y, t, &out);
  EXPECT_EQ(out.mu(0, 0), 0.0);
  c.time_scale = 1e3;
  KnnMap::Fit(train, c).Query(x, y, Eigen::Vector2d(25, 25), &out);
  EXPECT_EQ(out.mu(0, 0), -M_PI);
}

TEST(KnnDirectional, AverageLikelihoodOfOneNnIsTheMeanDensityAtTheNeighbours) {
  const DirectionalSamples train = RandomSamples(800, 11, 10.0, 50.0);
  const DirectionalSamples test = RandomSamples(300, 12, 10.0, 50.0);
  for (const double kappa : {10.0, 100.0}) {
    KnnConfig c;
    c.kappa = kappa;
    const KnnMap map = KnnMap::Fit(train, c);
    VonMisesMixtureBatch out;
    map.Query(test.x, test.y, test.t, &out);
    // Independent: nearest by brute force, density from std::cyl_bessel_i.
    double sum = 0;
    for (Eigen::Index i = 0; i < test.size(); ++i) {
      const Eigen::Index j = BruteNeighbours(train, c, test.x[i], test.y[i], test.t[i])[0];
      sum += std::exp(kappa * std::cos(test.theta[i] - train.theta[j])) /
             (2 * M_PI * std::cyl_bessel_i(0.0, kappa));
    }
    const double expect = sum / static_cast<double>(test.size());
    EXPECT_NEAR(AverageLikelihood(out, test.theta), expect, 1e-12 * expect) << kappa;
  }
}

TEST(KnnDirectional, LargeProblemMatchesBruteForceOnASubset) {
  // ~50k training points and 50k queries (the Edinburgh scale); checked on every 500th query.
  const DirectionalSamples train = RandomSamples(50000, 21, 15.0, 1000.0);
  const DirectionalSamples query = RandomSamples(50000, 22, 15.0, 1000.0);
  KnnConfig c;
  c.k = 3;
  c.use_time = true;
  c.time_scale = 0.05;
  const KnnMap map = KnnMap::Fit(train, c);
  EXPECT_EQ(map.size(), 50000);
  VonMisesMixtureBatch out;
  map.Query(query.x, query.y, query.t, &out);
  for (Eigen::Index i = 0; i < query.size(); i += 500) {
    const auto nn = BruteNeighbours(train, c, query.x[i], query.y[i], query.t[i]);
    for (int j = 0; j < c.k; ++j)
      EXPECT_EQ(out.mu(i, j), train.theta[nn[static_cast<std::size_t>(j)]]) << i << " " << j;
  }
}

TEST(KnnDirectional, QueryDoesNotAllocateWhenTheOutputHasItsShape) {
  const DirectionalSamples train = RandomSamples(500, 31, 10.0, 10.0);
  const DirectionalSamples query = RandomSamples(64, 32, 10.0, 10.0);
  KnnConfig c;
  c.k = 4;
  c.use_time = true;
  const KnnMap map = KnnMap::Fit(train, c);
  VonMisesMixtureBatch out;
  out.Resize(query.size(), c.k);
  g_allocations = 0;
  g_counting = true;
  map.Query(query.x, query.y, query.t, &out);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_EQ(out.alpha.cols(), 4);
}

TEST(KnnDirectional, BadConfigAndQueriesAreErrors) {
  const DirectionalSamples train = RandomSamples(5, 41, 1.0, 1.0);
  auto fit = [&](auto edit) {
    KnnConfig c;
    edit(&c);
    return KnnMap::Fit(train, c);
  };
  testing::ExpectErrorContains([&] { fit([](KnnConfig* c) { c->k = 0; }); }, {"k 0", ">= 1"});
  testing::ExpectErrorContains([&] { fit([](KnnConfig* c) { c->k = 6; }); },
                               {"k 6", "5 training samples"});
  testing::ExpectErrorContains([&] { fit([](KnnConfig* c) { c->kappa = 0; }); },
                               {"kappa 0", "> 0"});
  testing::ExpectErrorContains([&] { fit([](KnnConfig* c) { c->time_scale = -1; }); },
                               {"time_scale -1", "> 0"});
  DirectionalSamples bad = train;
  bad.theta[1] = 4.0;
  testing::ExpectErrorContains([&] { KnnMap::Fit(bad, KnnConfig{}); },
                               {"training samples", "sample 1", "outside [-pi, pi)"});

  const KnnMap map = fit([](KnnConfig* c) { c->use_time = true; });
  VonMisesMixtureBatch out;
  const Eigen::VectorXd two = Eigen::Vector2d(0.5, 0.5), three = Eigen::Vector3d(0.5, 0.5, 0.5);
  testing::ExpectErrorContains([&] { map.Query(two, three, two, &out); },
                               {"x [2]", "y [3]", "t [2]"});
  testing::ExpectErrorContains([&] { map.Query(two, two, Eigen::VectorXd(), &out); }, {"t [0]"});
  Eigen::VectorXd nan_t = two;
  nan_t[1] = std::nan("");
  testing::ExpectErrorContains([&] { map.Query(two, two, nan_t, &out); },
                               {"query 1", "t nan", "not finite"});
  testing::ExpectErrorContains([&] { map.Query(two, two, two, nullptr); }, {"no output batch"});
}

}  // namespace
}  // namespace foresight::directional
