// CMA-ES (inference/optim/cmaes.h) against Hansen's tutorial parameters, against evaluation counts
// reported for reference implementations, and for the GFCS contract: in-bounds candidates,
// injected warm-start candidates, statuses (never exceptions) for numeric trouble, and errors that
// name the bad field.

#include "inference/optim/cmaes.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "tests/test_util.h"

namespace foresight::optim {
namespace {

using foresight::testing::ExpectErrorContains;

double Sphere(const Eigen::VectorXd& x) { return x.squaredNorm(); }

/// Axis-parallel ellipsoid with condition number 1e6: sum_i 1e6^(i/(n-1)) x_i^2 (pycma ff.elli).
double Ellipsoid(const Eigen::VectorXd& x) {
  const double n = static_cast<double>(x.size());
  double f = 0;
  for (Eigen::Index i = 0; i < x.size(); ++i) f += std::pow(1e6, i / (n - 1)) * x[i] * x[i];
  return f;
}

/// Rosenbrock: sum_i 100 (x_i^2 - x_{i+1})^2 + (x_i - 1)^2, global minimum 0 at (1, ..., 1).
double Rosenbrock(const Eigen::VectorXd& x) {
  double f = 0;
  for (Eigen::Index i = 0; i + 1 < x.size(); ++i) {
    const double a = x[i] * x[i] - x[i + 1], b = x[i] - 1;
    f += 100 * a * a + b * b;
  }
  return f;
}

/// Rastrigin: 10 n + sum_i x_i^2 - 10 cos(2 pi x_i), global minimum 0 at 0.
double Rastrigin(const Eigen::VectorXd& x) {
  double f = 10.0 * x.size();
  for (Eigen::Index i = 0; i < x.size(); ++i) f += x[i] * x[i] - 10 * std::cos(2 * M_PI * x[i]);
  return f;
}

struct Runs {
  std::vector<std::int64_t> successful_evaluations;  // evaluations of the runs reaching the target
  int failures = 0;
  double Median() const {
    std::vector<std::int64_t> v = successful_evaluations;
    std::sort(v.begin(), v.end());
    return v.empty() ? std::numeric_limits<double>::quiet_NaN()
                     : static_cast<double>(v[v.size() / 2]);
  }
};

/// Runs Minimize from x0 = x0_value * ones(n) with seeds 1..seeds until f <= target.
Runs RunSeeds(double (*f)(const Eigen::VectorXd&), int n, double x0_value, double sigma0,
              double target, int population = 0, int seeds = 11) {
  Runs runs;
  for (int seed = 1; seed <= seeds; ++seed) {
    CmaEsOptions options;
    options.sigma0 = sigma0;
    options.seed = static_cast<std::uint64_t>(seed);
    options.target_cost = target;
    options.population = population;
    const CmaEsSummary s = Minimize(f, Eigen::VectorXd::Constant(n, x0_value), options);
    if (s.status == CmaEsStatus::kTargetReached)
      runs.successful_evaluations.push_back(s.evaluations);
    else
      ++runs.failures;
  }
  return runs;
}

/// Median within a factor of `factor` of `reference`, both ways.
void ExpectWithinFactor(double median, double reference, double factor) {
  EXPECT_GE(median, reference / factor) << "median " << median << " vs reference " << reference;
  EXPECT_LE(median, reference * factor) << "median " << median << " vs reference " << reference;
}

// ---------------------------------------------------------------------------------------------
// Table 1 of the tutorial.

TEST(CmaEsParameters, Dimension10MatchesAnIndependentComputation) {
  // Independent computation (Python, double precision) of Table 1 for n = 10, lambda = 10.
  const CmaEsParameters p = MakeCmaEsParameters(10, 0);
  EXPECT_EQ(p.lambda, 10);
  EXPECT_EQ(p.mu, 5);
  const double w[] = {0.45627264690340597, 0.2707530970017852, 0.16223111715866978,
                      0.08523354710016448, 0.025509591835974777};
  ASSERT_EQ(p.weights.size(), 5);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(p.weights[i], w[i], 1e-15) << i;
  EXPECT_NEAR(p.weights.sum(), 1.0, 1e-15);
  EXPECT_NEAR(p.mu_eff, 3.1672992814107017, 1e-13);
  EXPECT_NEAR(p.c_sigma, 0.28442858794636744, 1e-15);
  EXPECT_NEAR(p.d_sigma, 1.2844285879463675, 1e-15);
  EXPECT_NEAR(p.c_c, 0.29499038303562225, 1e-15);
  EXPECT_NEAR(p.c_1, 0.015283824524751714, 1e-16);
  EXPECT_NEAR(p.c_mu, 0.02015428276120837, 1e-16);
  EXPECT_EQ(p.c_m, 1.0);
  // chi_n against the exact E||N(0, I)|| = sqrt(2) Gamma((n+1)/2) / Gamma(n/2).
  const double exact_chi = std::sqrt(2.0) * std::exp(std::lgamma(5.5) - std::lgamma(5.0));
  EXPECT_NEAR(p.chi_n, exact_chi, 1e-3);
}

TEST(CmaEsParameters, WeightsSumToOneAndMuEffIsTheirVarianceMass) {
  for (int n : {1, 2, 3, 7, 10, 21, 50}) {
    for (int lambda : {0, 2, 3, 7, 40, 201}) {
      const CmaEsParameters p = MakeCmaEsParameters(n, lambda);
      EXPECT_NEAR(p.weights.sum(), 1.0, 1e-14);
      double sum = 0, sum_sq = 0;
      for (int i = 0; i < p.mu; ++i) {
        EXPECT_GT(p.weights[i], 0);
        if (i > 0) {
          EXPECT_LT(p.weights[i], p.weights[i - 1]);
        }
        sum += p.weights[i];
        sum_sq += p.weights[i] * p.weights[i];
      }
      EXPECT_NEAR(p.mu_eff, sum * sum / sum_sq, 1e-12);
      EXPECT_GE(p.mu_eff, 1.0);
      EXPECT_LE(p.mu_eff, p.mu + 1e-12);
      EXPECT_LE(p.c_1 + p.c_mu, 1.0 + 1e-15);  // (47) keeps a positive multiple of C
    }
  }
}

TEST(CmaEsParameters, DefaultPopulationAndWeightsMatchPycmaBanners) {
  // pycma (Hansen's reference code) prints the positive-weight part of its setting in its banner;
  // cma/test.py and cma/evolution_strategy.py doctests show, for dimensions 3, 4 and 10:
  //   "(3_w,7)-aCMA-ES (mu_w=2.3,w_1=58%)", "(4_w,8)-aCMA-ES (mu_w=2.6,w_1=52%)",
  //   "(5_w,10)-aCMA-ES (mu_w=3.2,w_1=45%)" (mu_w rounded to 0.1, w_1 truncated to a percent).
  struct Row {
    int n, lambda, mu;
    double mu_w, w_1;
  };
  for (const Row& r :
       {Row{3, 7, 3, 2.3, 0.58}, Row{4, 8, 4, 2.6, 0.52}, Row{10, 10, 5, 3.2, 0.45}}) {
    const CmaEsParameters p = MakeCmaEsParameters(r.n, 0);
    EXPECT_EQ(p.lambda, r.lambda) << "n = " << r.n;
    EXPECT_EQ(p.mu, r.mu) << "n = " << r.n;
    EXPECT_NEAR(p.mu_eff, r.mu_w, 0.05) << "n = " << r.n;
    EXPECT_EQ(std::floor(100 * p.weights[0]), std::round(100 * r.w_1)) << "n = " << r.n;
  }
}

// ---------------------------------------------------------------------------------------------
// One generation against the tutorial's Fig. 6, recomputed here with plain loops and Eigen's own
// inverse square root (the implementation uses its cached eigendecomposition).

struct ReferenceState {
  Eigen::VectorXd m, p_sigma, p_c;
  Eigen::MatrixXd C;
  double sigma = 0;
  int generations = 0;
  double h_sigma = -1;  // of the last step
};

/// Fig. 6, eqs. (41)-(47), for the steps Y [n x lambda] (column k: (x_k - m) / sigma, clipped for
/// injected columns) and their costs.
ReferenceState ReferenceStep(const ReferenceState& s, const Eigen::MatrixXd& Y,
                             const Eigen::VectorXd& costs, const CmaEsParameters& p) {
  const int n = p.n;
  std::vector<int> order(p.lambda);
  for (int k = 0; k < p.lambda; ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return costs[a] < costs[b]; });
  Eigen::VectorXd y_w = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < p.mu; ++i)
    for (int r = 0; r < n; ++r) y_w[r] += p.weights[i] * Y(r, order[i]);
  ReferenceState t = s;
  t.generations = s.generations + 1;
  t.m = s.m + s.sigma * y_w;
  const Eigen::MatrixXd inv_sqrt_C =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s.C).operatorInverseSqrt();
  t.p_sigma = (1 - p.c_sigma) * s.p_sigma +
              std::sqrt(p.c_sigma * (2 - p.c_sigma) * p.mu_eff) * inv_sqrt_C * y_w;
  const double norm = t.p_sigma.norm();
  t.sigma = s.sigma * std::exp(p.c_sigma / p.d_sigma * (norm / p.chi_n - 1));
  const double decay = 1 - std::pow(1 - p.c_sigma, 2 * t.generations);
  t.h_sigma = norm / std::sqrt(decay) < (1.4 + 2.0 / (n + 1)) * p.chi_n ? 1 : 0;
  t.p_c = (1 - p.c_c) * s.p_c + t.h_sigma * std::sqrt(p.c_c * (2 - p.c_c) * p.mu_eff) * y_w;
  const double delta = (1 - t.h_sigma) * p.c_c * (2 - p.c_c);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      double rank_mu = 0;
      for (int i = 0; i < p.mu; ++i) rank_mu += p.weights[i] * Y(r, order[i]) * Y(c, order[i]);
      t.C(r, c) = (1 + p.c_1 * delta - p.c_1 - p.c_mu) * s.C(r, c) + p.c_1 * t.p_c[r] * t.p_c[c] +
                  p.c_mu * rank_mu;
    }
  }
  return t;
}

TEST(CmaEs, GenerationsMatchTheTutorialEquations) {
  const int n = 3;
  CmaEsOptions options;
  options.sigma0 = 0.7;
  options.seed = 11;
  const Eigen::Vector3d mean0(0.2, -0.4, 1.0);
  CmaEs es(mean0, options);
  const CmaEsParameters& p = es.parameters();
  ASSERT_LT(p.eigen_interval, p.lambda);  // n = 3: C is decomposed after every generation
  ReferenceState s{mean0,
                   Eigen::VectorXd::Zero(n),
                   Eigen::VectorXd::Zero(n),
                   Eigen::MatrixXd::Identity(n, n),
                   options.sigma0,
                   0,
                   -1};
  std::vector<double> h_sigmas;
  for (int g = 0; g < 4; ++g) {
    Eigen::MatrixXd Y(n, p.lambda);
    if (g == 0) {
      // All columns injected far away: the clipped step is long, p_sigma is long, h_sigma = 0.
      const Eigen::Vector3d far(30, -20, 10);
      es.Inject(far.replicate(1, p.lambda));
      const Eigen::VectorXd y = (far - s.m) / s.sigma;
      const double length =
          (Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s.C).operatorInverseSqrt() * y).norm();
      Y = (y * std::min(1.0, p.c_y / length)).replicate(1, p.lambda);
    }
    const Eigen::MatrixXd& X = es.Ask();
    if (g > 0) Y = (X.colwise() - s.m) / s.sigma;
    Eigen::VectorXd costs(p.lambda);
    for (int k = 0; k < p.lambda; ++k) costs[k] = Sphere(X.col(k)) + 1e-3 * k;  // no ties
    es.Tell(costs);
    s = ReferenceStep(s, Y, costs, p);
    h_sigmas.push_back(s.h_sigma);
    EXPECT_TRUE(foresight::testing::MatricesNear(es.mean(), s.m, 1e-12)) << "generation " << g;
    EXPECT_NEAR(es.sigma(), s.sigma, 1e-12 * s.sigma) << "generation " << g;
    EXPECT_TRUE(foresight::testing::MatricesNear(es.covariance(), s.C, 1e-12))
        << "generation " << g;
  }
  EXPECT_EQ(h_sigmas.front(), 0.0);  // the stall branch was exercised
  EXPECT_NE(std::find(h_sigmas.begin(), h_sigmas.end(), 1.0), h_sigmas.end());  // and the other
}

// ---------------------------------------------------------------------------------------------
// Evaluation counts. References and how sure we are of them:
//  [pycma-purecma] cma/purecma.py (Hansen), fmin docstring: ellipsoid (condition 1e6) in 3-D from
//      x0 = 0.5, sigma0 = 0.3 with positive weights: f = 4.8e-13 after 1400 evaluations (one run).
//  [pycma-fmin] cma/evolution_strategy.py (Hansen), fmin doctest: Rosenbrock 10-D from x0 = 0.1,
//      sigma0 = 0.3 reaches f < 1e-12 in < 8000 evaluations (aCMA, i.e. with negative weights).
//  [brief] figures for the default-lambda CMA-ES in 10-D to f = 1e-8 that the task quoted from
//      Hansen and Ostermeier (2001) / Hansen et al. (2003): sphere ~1.5e3 (x0 = 1, sigma0 = 1),
//      ellipsoid ~5.5e3, Rosenbrock ~6.5e3. The papers' tables were not available to check
//      (not in the reference corpus); these are order-of-magnitude references only.
// Measured (11 seeds, libstdc++): sphere 1360, ellipsoid 10-D 5820, ellipsoid 3-D to 4.8e-13
// 1250, Rosenbrock 10-D to 1e-8 5940 and to 1e-12 6540.

TEST(CmaEs, SphereEvaluationsMatchThePublishedOrder) {
  const Runs runs = RunSeeds(Sphere, 10, 1.0, 1.0, 1e-8);
  EXPECT_EQ(runs.failures, 0);
  ExpectWithinFactor(runs.Median(), 1.5e3, 1.5);  // [brief]
}

TEST(CmaEs, EllipsoidEvaluationsMatchTheReferenceRun) {
  const Runs runs3 = RunSeeds(Ellipsoid, 3, 0.5, 0.3, 4.8e-13);
  EXPECT_EQ(runs3.failures, 0);
  ExpectWithinFactor(runs3.Median(), 1400, 1.5);  // [pycma-purecma]
  const Runs runs10 = RunSeeds(Ellipsoid, 10, 1.0, 1.0, 1e-8);
  EXPECT_EQ(runs10.failures, 0);
  ExpectWithinFactor(runs10.Median(), 5.5e3, 1.5);  // [brief]
}

TEST(CmaEs, RosenbrockReachesTheGlobalMinimum) {
  // Restart-free CMA-ES sometimes ends in Rosenbrock's local minimum near x_1 = -1 (pycma's
  // cma/test.py reports ~20% in 4-D from x0 = -1 with sigma0 = 0.01); from x0 = 0.1 no seed did.
  const Runs runs = RunSeeds(Rosenbrock, 10, 0.1, 0.3, 1e-12);
  EXPECT_LE(runs.failures, 1);
  EXPECT_LE(runs.Median(), 8000);  // [pycma-fmin]
  const Runs runs8 = RunSeeds(Rosenbrock, 10, 0.1, 0.3, 1e-8);
  EXPECT_LE(runs8.failures, 1);
  ExpectWithinFactor(runs8.Median(), 6.5e3, 1.5);  // [brief]
}

TEST(CmaEs, RastriginNeedsALargePopulation) {
  // Hansen and Kern (PPSN 2004): increasing lambda markedly raises the chance of locating
  // Rastrigin's global optimum. 5-D, x0 = 3 (distance 3 per coordinate), sigma0 = 2. Measured over
  // 21 seeds: default lambda = 8: 0/21; lambda = 100: 14/21; 200: 16/21; 400: 21/21.
  const Runs small = RunSeeds(Rastrigin, 5, 3.0, 2.0, 1e-8, 0);
  const Runs medium = RunSeeds(Rastrigin, 5, 3.0, 2.0, 1e-8, 200);
  const Runs large = RunSeeds(Rastrigin, 5, 3.0, 2.0, 1e-8, 400);
  const int n_small = static_cast<int>(small.successful_evaluations.size());
  const int n_medium = static_cast<int>(medium.successful_evaluations.size());
  const int n_large = static_cast<int>(large.successful_evaluations.size());
  EXPECT_LE(n_small, 1);
  EXPECT_GE(n_medium, 5);
  EXPECT_GE(n_large, 10);
  EXPECT_LE(n_small, n_medium);
  EXPECT_LE(n_medium, n_large);
}

// ---------------------------------------------------------------------------------------------
// Bounds, determinism, ask/tell contract, injection.

TEST(CmaEs, BoundedOptimumOnTheBoundIsReachedWithInBoundsCandidates) {
  // 7 joints with limits [-1, 1]; the unconstrained optimum c lies outside the box in four
  // coordinates, so the constrained optimum is clamp(c) (the cost is separable).
  const int n = 7;
  Eigen::VectorXd c(n);
  c << 2.0, 0.3, -3.0, 0.5, 1.5, -0.2, -1.0;
  const Eigen::VectorXd lower = Eigen::VectorXd::Constant(n, -1), upper = -lower;
  const Eigen::VectorXd x_star = c.cwiseMax(lower).cwiseMin(upper);
  auto f = [&](const Eigen::VectorXd& x) { return (x - c).squaredNorm(); };
  for (std::uint64_t seed : {1, 2, 3}) {
    CmaEsOptions options;
    options.sigma0 = 0.5;
    options.seed = seed;
    options.lower = lower;
    options.upper = upper;
    options.target_cost = f(x_star) + 1e-10;
    CmaEs es(Eigen::VectorXd::Zero(n), options);
    Eigen::VectorXd costs(es.population());
    while (es.status() == CmaEsStatus::kRunning) {
      const Eigen::MatrixXd& X = es.Ask();
      for (Eigen::Index k = 0; k < X.cols(); ++k) {
        ASSERT_TRUE((X.col(k).array() >= lower.array()).all() &&
                    (X.col(k).array() <= upper.array()).all())
            << "generation " << es.generation() << " candidate " << k << ": "
            << X.col(k).transpose();
        costs[k] = f(X.col(k));
      }
      es.Tell(costs);
    }
    EXPECT_EQ(es.status(), CmaEsStatus::kTargetReached) << "seed " << seed;
    EXPECT_TRUE(foresight::testing::MatricesNear(es.best_x(), x_star, 1e-4)) << "seed " << seed;
    EXPECT_TRUE(foresight::testing::MatricesNear(es.mean(), x_star, 1e-2)) << "seed " << seed;
    EXPECT_LT(es.evaluations(), 5000) << "seed " << seed;
  }
}

TEST(CmaEs, SameSeedGivesTheSameRun) {
  CmaEsOptions options;
  options.seed = 7;
  options.max_evaluations = 500;
  const CmaEsSummary a = Minimize(Rosenbrock, Eigen::VectorXd::Zero(6), options);
  const CmaEsSummary b = Minimize(Rosenbrock, Eigen::VectorXd::Zero(6), options);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.best_cost, b.best_cost);
  EXPECT_EQ(a.best_x, b.best_x);
  EXPECT_EQ(a.final_sigma, b.final_sigma);
  options.seed = 8;
  const CmaEsSummary c = Minimize(Rosenbrock, Eigen::VectorXd::Zero(6), options);
  EXPECT_NE(a.best_cost, c.best_cost);
}

TEST(CmaEs, AskTwiceReturnsTheSameBatchAndStopsAtTheBudget) {
  CmaEsOptions options;
  options.max_evaluations = 1000;
  CmaEs es(Eigen::VectorXd::Ones(21), options);  // GFCS-sized: lambda = 4 + floor(3 ln 21) = 13
  ASSERT_EQ(es.population(), 13);
  const Eigen::MatrixXd first = es.Ask();
  EXPECT_EQ(first, es.Ask());
  Eigen::VectorXd costs(13);
  bool told = false;
  while (es.status() == CmaEsStatus::kRunning) {
    const Eigen::MatrixXd& X = told ? es.Ask() : first;
    for (int k = 0; k < 13; ++k) costs[k] = Sphere(X.col(k));
    es.Tell(costs);
    told = true;
  }
  EXPECT_EQ(es.status(), CmaEsStatus::kMaxEvaluations);
  EXPECT_EQ(es.evaluations(), 988);  // 76 generations; the 77th would exceed 1000
  EXPECT_EQ(es.generation(), 76);
}

TEST(CmaEs, InjectedStepsAreClippedToMahalanobisLengthCy) {
  // Hansen 2011: y <- y min(1, c_y / ||C^{-1/2} y||). With every column injected at the same point
  // <y>_w is that clipped step, so the first mean update (42) is exactly m + sigma0 * clip(y).
  const int n = 5;
  CmaEsOptions options;
  options.sigma0 = 0.1;
  CmaEs es(Eigen::VectorXd::Zero(n), options);
  const double c_y = std::sqrt(5.0) + 10.0 / 7.0;
  EXPECT_NEAR(es.parameters().c_y, c_y, 1e-15);
  const int lambda = es.population();
  Eigen::VectorXd far = Eigen::VectorXd::Zero(n);
  far[0] = 100 * options.sigma0;  // Mahalanobis length 100 (C = I at first)
  es.Inject(far.replicate(1, lambda));
  const Eigen::MatrixXd& X = es.Ask();
  EXPECT_EQ(X, far.replicate(1, lambda));  // the caller evaluates the injected point as given
  es.Tell(Eigen::VectorXd::Zero(lambda));
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(n);
  expected[0] = options.sigma0 * c_y;
  EXPECT_TRUE(foresight::testing::MatricesNear(es.mean(), expected, 1e-14));
  EXPECT_EQ(es.best_cost(), 0.0);
  EXPECT_EQ(es.best_x(), far);

  // A near point (length 0.5 < c_y) is not clipped: the mean moves onto it.
  CmaEs near_es(Eigen::VectorXd::Zero(n), options);
  Eigen::VectorXd near = Eigen::VectorXd::Zero(n);
  near[1] = 0.5 * options.sigma0;
  near_es.Inject(near.replicate(1, lambda));
  near_es.Ask();
  near_es.Tell(Eigen::VectorXd::Ones(lambda));
  EXPECT_TRUE(foresight::testing::MatricesNear(near_es.mean(), near, 1e-15));
}

TEST(CmaEs, WarmStartCandidatesAreEvaluatedProjectedAndSpeedUpTheRun) {
  // GFCS-like: the first batch comes partly from a learned sampler (here: points near the
  // optimum, one outside the joint limits), the rest from CMA-ES.
  const int n = 7;
  Eigen::VectorXd c = Eigen::VectorXd::LinSpaced(n, -0.6, 0.6);
  auto f = [&](const Eigen::VectorXd& x) { return (x - c).squaredNorm(); };
  CmaEsOptions options;
  options.sigma0 = 0.5;
  options.lower = Eigen::VectorXd::Constant(n, -1);
  options.upper = Eigen::VectorXd::Constant(n, 1);
  options.target_cost = 1e-8;
  Eigen::MatrixXd warm(n, 3);
  warm.col(0) = c + Eigen::VectorXd::Constant(n, 0.01);
  warm.col(1) = c - Eigen::VectorXd::Constant(n, 0.02);
  warm.col(2) = Eigen::VectorXd::Constant(n, 3.0);  // outside the box: projected to the corner
  std::int64_t cold_evaluations = 0, warm_evaluations = 0;
  for (bool use_warm : {false, true}) {
    CmaEs es(Eigen::VectorXd::Zero(n), options);
    if (use_warm) es.Inject(warm);
    Eigen::VectorXd costs(es.population());
    while (es.status() == CmaEsStatus::kRunning) {
      const Eigen::MatrixXd& X = es.Ask();
      if (use_warm && es.generation() == 0) {
        EXPECT_EQ(X.col(0), warm.col(0));
        EXPECT_EQ(X.col(1), warm.col(1));
        EXPECT_EQ(X.col(2), Eigen::VectorXd::Ones(n));
      }
      for (Eigen::Index k = 0; k < X.cols(); ++k) costs[k] = f(X.col(k));
      es.Tell(costs);
      if (use_warm && es.generation() == 1) {
        EXPECT_EQ(es.best_x(), warm.col(0));
      }
    }
    EXPECT_EQ(es.status(), CmaEsStatus::kTargetReached);
    (use_warm ? warm_evaluations : cold_evaluations) = es.evaluations();
  }
  EXPECT_LT(warm_evaluations, cold_evaluations);
}

// ---------------------------------------------------------------------------------------------
// Expected numeric outcomes are statuses.

TEST(CmaEs, NonFiniteCostsAreRankedLastAndCounted) {
  // A failure region (NaN) and an infinite wall, as a rollout simulator might report.
  auto f = [](const Eigen::VectorXd& x) {
    if (x[1] < -0.5) return std::numeric_limits<double>::quiet_NaN();
    if (x[2] > 1.2) return std::numeric_limits<double>::infinity();
    return x.squaredNorm();
  };
  CmaEsOptions options;
  options.target_cost = 1e-8;
  options.sigma0 = 0.5;
  const CmaEsSummary s = Minimize(f, Eigen::VectorXd::Constant(5, 0.5), options);
  EXPECT_EQ(s.status, CmaEsStatus::kTargetReached) << s.BriefReport();
  EXPECT_GT(s.non_finite_costs, 0);
  EXPECT_TRUE(std::isfinite(s.best_cost));
  EXPECT_TRUE(s.best_x.allFinite());
}

TEST(CmaEs, AGenerationWithoutFiniteCostsStopsWithAStatus) {
  CmaEs es(Eigen::VectorXd::Zero(4), CmaEsOptions());
  es.Ask();
  Eigen::VectorXd costs =
      Eigen::VectorXd::Constant(es.population(), std::numeric_limits<double>::quiet_NaN());
  costs[1] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(es.Tell(costs), CmaEsStatus::kNonFiniteCosts);
  EXPECT_EQ(es.non_finite_costs(), es.population());
  EXPECT_EQ(es.evaluations(), es.population());
  EXPECT_TRUE(es.mean().allFinite());
  ExpectErrorContains([&] { es.Ask(); }, {"stopped", "non_finite_costs"});
}

TEST(CmaEs, DegenerateCovarianceStopsWithConditionStatus) {
  // f = x_1^2 in 5-D: four directions are irrelevant, C becomes ever more ill-conditioned
  // (tutorial B.3 ConditionCov). TolFun/TolX are disabled so that the condition limit acts.
  CmaEsOptions options;
  options.tol_fun = 0;
  options.tol_x = 0;
  options.max_condition = 1e10;
  CmaEs es(Eigen::VectorXd::Ones(5), options);
  Eigen::VectorXd costs(es.population());
  while (es.status() == CmaEsStatus::kRunning) {
    const Eigen::MatrixXd& X = es.Ask();
    for (Eigen::Index k = 0; k < X.cols(); ++k) costs[k] = X(0, k) * X(0, k);
    es.Tell(costs);
  }
  EXPECT_EQ(es.status(), CmaEsStatus::kConditionCov);
  EXPECT_GT(es.condition(), 1e10);
  EXPECT_TRUE(es.covariance().allFinite());
  EXPECT_TRUE(es.mean().allFinite());
  EXPECT_TRUE(std::isfinite(es.sigma()));
}

TEST(CmaEs, OverflowingStepSizeStopsWithNumericalErrorAndKeepsAFiniteState) {
  // A linear cost makes sigma grow geometrically; from sigma0 = 1e300 the next samples would
  // overflow. The update is discarded and the run stops; no NaN/inf reaches the caller.
  CmaEsOptions options;
  options.sigma0 = 1e300;
  const CmaEsSummary s =
      Minimize([](const Eigen::VectorXd& x) { return x[0]; }, Eigen::VectorXd::Zero(5), options);
  EXPECT_EQ(s.status, CmaEsStatus::kNumericalError) << s.BriefReport();
  EXPECT_TRUE(std::isfinite(s.final_sigma));
  EXPECT_TRUE(s.best_x.allFinite());
}

TEST(CmaEs, FlatCostIncreasesSigmaThenStopsOnTolFun) {
  CmaEsOptions options;
  CmaEs es(Eigen::VectorXd::Zero(5), options);
  while (es.status() == CmaEsStatus::kRunning) {
    es.Ask();
    es.Tell(Eigen::VectorXd::Constant(es.population(), 1.0));
  }
  EXPECT_EQ(es.status(), CmaEsStatus::kTolFun);
  EXPECT_GT(es.flat_generations(), 0);
  EXPECT_GT(es.sigma(), options.sigma0);  // tutorial B.4: sigma *= exp(0.2 + c_sigma / d_sigma)
}

TEST(CmaEs, TolXStopsWhenTheDistributionHasCollapsed) {
  CmaEsOptions options;
  options.tol_fun = 0;
  const CmaEsSummary s = Minimize(Sphere, Eigen::VectorXd::Ones(4), options);
  EXPECT_EQ(s.status, CmaEsStatus::kTolX) << s.BriefReport();
  EXPECT_LT(s.best_cost, 1e-20);
  const std::string report = s.BriefReport();
  EXPECT_NE(report.find("tol_x"), std::string::npos) << report;
  EXPECT_EQ(report.find('\n'), std::string::npos) << report;
}

// ---------------------------------------------------------------------------------------------
// Bad input.

TEST(CmaEsOptions, IsValidNamesTheBadFieldAndValue) {
  std::string error;
  EXPECT_TRUE(CmaEsOptions().IsValid(&error));
  EXPECT_TRUE(CmaEsOptions().IsValid(nullptr));
  struct Case {
    std::function<void(CmaEsOptions*)> edit;
    std::vector<std::string> parts;
  };
  const std::vector<Case> cases = {
      {[](CmaEsOptions* o) { o->population = 1; }, {"population = 1"}},
      {[](CmaEsOptions* o) { o->sigma0 = -0.5; }, {"sigma0 = -0.5", "> 0"}},
      {[](CmaEsOptions* o) { o->sigma0 = std::numeric_limits<double>::quiet_NaN(); }, {"sigma0"}},
      {[](CmaEsOptions* o) { o->max_evaluations = -3; }, {"max_evaluations = -3"}},
      {[](CmaEsOptions* o) { o->tol_fun = -1; }, {"tol_fun = -1"}},
      {[](CmaEsOptions* o) { o->tol_x = -2; }, {"tol_x = -2"}},
      {[](CmaEsOptions* o) { o->max_condition = 0.5; }, {"max_condition = 0.5"}},
      {[](CmaEsOptions* o) { o->target_cost = std::numeric_limits<double>::quiet_NaN(); },
       {"target_cost"}},
      {[](CmaEsOptions* o) {
         o->lower = Eigen::Vector2d(0, 2);
         o->upper = Eigen::Vector2d(1, 1);
       },
       {"lower[1] = 2", "upper[1] = 1"}},
      {[](CmaEsOptions* o) {
         o->lower = Eigen::Vector2d(0, 0);
         o->upper = Eigen::Vector3d(1, 1, 1);
       },
       {"lower has size 2", "upper has size 3"}},
  };
  for (const Case& c : cases) {
    CmaEsOptions o;
    c.edit(&o);
    error.clear();
    EXPECT_FALSE(o.IsValid(&error));
    for (const auto& p : c.parts) EXPECT_NE(error.find(p), std::string::npos) << error;
    // The constructor throws the same message.
    ExpectErrorContains([&] { CmaEs es(Eigen::VectorXd::Zero(2), o); }, c.parts);
  }
}

TEST(CmaEs, BadInputThrowsErrorNamingTheFieldAndValue) {
  CmaEsOptions bounded;
  bounded.lower = Eigen::VectorXd::Constant(3, -1);
  bounded.upper = Eigen::VectorXd::Constant(3, 1);
  ExpectErrorContains([&] { CmaEs es(Eigen::VectorXd::Zero(2), bounded); },
                      {"lower has size 3", "dimension n = 2"});
  ExpectErrorContains([&] { CmaEs es(Eigen::Vector3d(0, 5, 0), bounded); },
                      {"mean0[1] = 5", "outside the bounds"});
  ExpectErrorContains([&] { CmaEs es(Eigen::VectorXd(0), CmaEsOptions{}); }, {"mean0 is empty"});
  ExpectErrorContains(
      [&] {
        CmaEs es(Eigen::Vector2d(0, std::numeric_limits<double>::infinity()), CmaEsOptions());
      },
      {"mean0[1] = inf"});

  CmaEsOptions options;
  options.population = 6;
  CmaEs es(Eigen::VectorXd::Zero(2), options);
  ExpectErrorContains([&] { es.Tell(Eigen::VectorXd::Zero(6)); }, {"before Ask"});
  ExpectErrorContains([&] { es.Inject(Eigen::MatrixXd::Zero(3, 1)); },
                      {"3 rows", "dimension n = 2"});
  ExpectErrorContains([&] { es.Inject(Eigen::MatrixXd::Zero(2, 7)); }, {"7 columns", "lambda = 6"});
  Eigen::MatrixXd nan_candidate = Eigen::MatrixXd::Zero(2, 1);
  nan_candidate(1, 0) = std::numeric_limits<double>::quiet_NaN();
  ExpectErrorContains([&] { es.Inject(nan_candidate); }, {"candidates(1, 0) = nan"});
  es.Ask();
  ExpectErrorContains([&] { es.Tell(Eigen::VectorXd::Zero(3)); },
                      {"costs has size 3", "lambda = 6"});
  ExpectErrorContains([&] { es.Inject(Eigen::MatrixXd::Zero(2, 1)); }, {"Inject after Ask"});
  es.Tell(Eigen::VectorXd::Zero(6));
  ExpectErrorContains([&] { es.Tell(Eigen::VectorXd::Zero(6)); }, {"before Ask"});
  ExpectErrorContains([&] { MakeCmaEsParameters(0, 0); }, {"dimension n = 0"});
  ExpectErrorContains([&] { Minimize(nullptr, Eigen::VectorXd::Zero(2), CmaEsOptions()); },
                      {"cost function is empty"});
}

}  // namespace
}  // namespace foresight::optim
