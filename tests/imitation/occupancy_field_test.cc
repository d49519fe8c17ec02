// The occupancy field against central finite differences and the mapping engine's HingeMap; the
// occupancy fit (IRLS) recovering a disc and a sphere from lattice samples.

#include "inference/imitation/occupancy_field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "inference/mapping/hinge_map.h"
#include "models/imitation/occupancy_fit.h"
#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

// No truncation inside [-0.3, 0.3]^D: the field is smooth there.
template <int D>
RbfGridSpec<D> SmoothGrid() {
  RbfGridSpec<D> s;
  s.lower = Vec<D>::Constant(D == 2 ? -0.3 : -0.2);
  s.counts.fill(D == 2 ? 7 : 5);
  s.spacing = 0.1;
  s.gamma = 30;
  s.cutoff_radius = D == 2 ? 1.0 : 0.75;
  return s;
}

template <int D>
Vec<D> RandomPoint(std::mt19937_64* rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  Vec<D> p;
  for (int a = 0; a < D; ++a) p[a] = u(*rng);
  return p;
}

// Weights N(0, scale^2) on every inducing state, bias -0.3.
template <int D>
OccupancyField<D> RandomField(const RbfGrid<D>& grid, double scale, std::mt19937_64* rng) {
  std::normal_distribution<double> n01;
  Eigen::VectorXd w(grid.size());
  for (auto& v : w) v = scale * n01(*rng);
  return OccupancyField<D>(grid, w, -0.3);
}

template <int D>
void CheckDerivatives(std::uint64_t seed) {
  const RbfGrid<D> grid(SmoothGrid<D>());
  std::mt19937_64 rng(seed);
  const OccupancyField<D> field = RandomField(grid, 1.5, &rng);
  const Eigen::VectorXd& w = field.weights();
  auto ws = field.MakeWorkspace();
  const double h = 1e-5;
  for (int n = 0; n < 20; ++n) {
    const Vec<D> s = RandomPoint<D>(&rng, -0.15, 0.15);
    OccupancyValue<D> v, plus, minus;
    field.Evaluate(s, ws.get(), true, &v);
    EXPECT_GT(v.p, 0);
    EXPECT_LT(v.p, 1);
    EXPECT_EQ(field.Probability(s, ws.get()), v.p);
    // Independent p: dense features over all states.
    double f = -0.3;
    for (int t = 0; t < grid.size(); ++t)
      f += w[t] * std::exp(-30 * (s - grid.Centre(t)).squaredNorm());
    EXPECT_NEAR(v.p, 1 / (1 + std::exp(-f)), 1e-14);
    Vec<D> grad_fd;
    Mat<D> hess_fd;
    for (int a = 0; a < D; ++a) {
      Vec<D> e = Vec<D>::Zero();
      e[a] = h;
      field.Evaluate(s + e, ws.get(), false, &plus);
      field.Evaluate(s - e, ws.get(), false, &minus);
      grad_fd[a] = (plus.p - minus.p) / (2 * h);
      hess_fd.col(a) = (plus.gradient - minus.gradient) / (2 * h);
    }
    EXPECT_TRUE(testing::MatricesNear(v.gradient, grad_fd, 1e-7 * (1 + v.gradient.norm())));
    EXPECT_TRUE(testing::MatricesNear(v.hessian, hess_fd, 1e-6 * (1 + v.hessian.norm())));
    EXPECT_TRUE(testing::MatricesNear(v.hessian, v.hessian.transpose(), 1e-12));
    OccupancyValue<D> no_hessian;
    field.Evaluate(s, ws.get(), false, &no_hessian);
    EXPECT_EQ(no_hessian.p, v.p);
    EXPECT_TRUE(testing::MatricesNear(no_hessian.gradient, v.gradient, 0));
  }
}

TEST(OccupancyField, DerivativesMatchFiniteDifferences2D) { CheckDerivatives<2>(1); }
TEST(OccupancyField, DerivativesMatchFiniteDifferences3D) { CheckDerivatives<3>(2); }

// Evaluate sums over features row by row of the separable window; the same sums over the feature
// list RbfGrid::Evaluate gives (the definition in the header) must agree to rounding, with the
// cut-off active (a small radius against the grid) and points near and off the grid's edges.
template <int D>
void CheckRowSumsEqualTheFeatureList(std::uint64_t seed) {
  RbfGridSpec<D> spec;
  spec.lower = Vec<D>::Constant(-0.5);
  spec.counts.fill(D == 2 ? 21 : 11);
  spec.spacing = D == 2 ? 0.05 : 0.1;
  spec.gamma = 120;
  spec.cutoff_radius = 0.27;
  const RbfGrid<D> grid(spec);
  std::mt19937_64 rng(seed);
  const OccupancyField<D> field = RandomField(grid, 2.0, &rng);
  const Eigen::VectorXd& w = field.weights();
  auto ws = field.MakeWorkspace();
  RbfFeatures<D> features;
  int with_features = 0;
  for (int k = 0; k < 300; ++k) {
    const Vec<D> s = RandomPoint<D>(&rng, -0.8, 0.8);
    grid.Evaluate(s, &features);
    double sum = 0;
    Vec<D> first = Vec<D>::Zero();
    Mat<D> second = Mat<D>::Zero();
    for (int i = 0; i < features.count; ++i) {
      const double a = w[features.index[i]] * features.phi[i];
      sum += a;
      first += a * features.offset[i];
      second += a * features.offset[i] * features.offset[i].transpose();
    }
    with_features += features.count > 0;
    const double g = spec.gamma, p = 1 / (1 + std::exp(0.3 - sum)), dp = p * (1 - p);
    const Vec<D> grad_f = -2 * g * first;
    const Mat<D> hess_f = 4 * g * g * second - 2 * g * sum * Mat<D>::Identity();
    OccupancyValue<D> v;
    field.Evaluate(s, ws.get(), true, &v);
    EXPECT_NEAR(v.p, p, 1e-14) << s.transpose();
    EXPECT_TRUE(testing::MatricesNear(v.gradient, dp * grad_f, 1e-11 * (1 + grad_f.norm())));
    const Mat<D> hess = dp * ((1 - 2 * p) * grad_f * grad_f.transpose() + hess_f);
    EXPECT_TRUE(testing::MatricesNear(v.hessian, hess, 1e-10 * (1 + hess.norm())));
    EXPECT_EQ(field.Probability(s, ws.get()), v.p);  // the same sums, to the bit
    if (features.count == 0) {  // exactly zero outside the support (the flows stop there)
      EXPECT_TRUE(v.gradient.isZero(0) && v.hessian.isZero(0));
    }
  }
  EXPECT_GT(with_features, 100);
  EXPECT_LT(with_features, 300);
}

TEST(OccupancyField, RowSumsEqualTheFeatureList2D) { CheckRowSumsEqualTheFeatureList<2>(5); }
TEST(OccupancyField, RowSumsEqualTheFeatureList3D) { CheckRowSumsEqualTheFeatureList<3>(6); }

TEST(OccupancyField, FromHingeMapEqualsHingeMapQuery) {
  HingeGridConfig c;
  c.x_min = -1;
  c.x_max = 4;
  c.y_min = 0.5;
  c.y_max = 4.5;
  c.spacing = 0.25;
  c.gamma = 12;
  c.cutoff_radius = 0.8;
  const HingeGrid grid(c);
  const occupancy::HingeMap map =
      testing::RandomHingeMap(occupancy::HingeMapKind::kHilbert, grid, 3);
  const OccupancyField<2> field = OccupancyField<2>::FromHingeMap(map);
  EXPECT_EQ(field.grid().size(), grid.size());
  occupancy::MapWorkspace mws = map.MakeWorkspace();
  auto ws = field.MakeWorkspace();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(-1, 3.75), uy(0.5, 4.25);
  for (int n = 0; n < 300; ++n) {
    const Vec<2> s(ux(rng), uy(rng));
    const occupancy::QueryResult q = map.Query(s[0], s[1], &mws);
    OccupancyValue<2> v;
    field.Evaluate(s, ws.get(), false, &v);
    EXPECT_NEAR(v.p, q.probability, 1e-12) << s.transpose();
    EXPECT_NEAR(v.gradient[0], q.dp_dx, 1e-10);
    EXPECT_NEAR(v.gradient[1], q.dp_dy, 1e-10);
  }
  testing::ExpectErrorContains([&] { OccupancyField<3>::FromHingeMap(map); }, {"2-D"});
}

TEST(OccupancyField, BadInputIsAnError) {
  const RbfGrid<2> grid(SmoothGrid<2>());
  testing::ExpectErrorContains(
      [&] { OccupancyField<2> f(grid, Eigen::VectorXd::Zero(3), 0, "obstacle map"); },
      {"obstacle map", "3 weights", "49"});
  testing::ExpectErrorContains(
      [&] { OccupancyField<2> f(grid, Eigen::VectorXd::Zero(49), std::nan("")); }, {"bias"});
}

// ---- the bicubic table ------------------------------------------------------------------------

// The error bounds of the C1 bicubic Hermite interpolant of f: O(h^4) for f, O(h^3) for grad f,
// O(h^2) for Hess f, against the kernel width sigma = 1 / sqrt(2 gamma): the errors at h = sigma /
// 8 and at h / 2 fall by at least 2^4 - 40 %, 2^3 - 40 %, 2^2 - 40 %, and at h = sigma / 16 the
// table is within 1e-5 (p), 1e-3 (grad p) and 3e-2 (Hess p) of the exact field relative to each
// quantity's largest size over the points. Every point inside the support; the field's weights are
// random, so it has no special shape.
TEST(OccupancyFieldTable, ConvergesToTheExactFieldAtTheBicubicRates) {
  RbfGridSpec<2> spec;
  spec.lower = Vec<2>(-0.3, -0.2);
  spec.counts = {7, 6};
  spec.spacing = 0.1;
  spec.gamma = 60;
  spec.cutoff_radius = 0.6;  // gamma r^2 = 21.6: truncation 4e-10
  const RbfGrid<2> grid(spec);
  std::mt19937_64 rng(11);
  const OccupancyField<2> exact = RandomField(grid, 1.5, &rng);
  auto ws = exact.MakeWorkspace();
  std::vector<Vec<2>> points;
  for (int n = 0; n < 400; ++n) points.push_back(RandomPoint<2>(&rng, -0.45, 0.45));
  const double sigma = 1 / std::sqrt(2 * spec.gamma);
  // Largest error of p, grad p and Hess p over the points, and each quantity's largest size.
  struct Errors {
    double p = 0, grad = 0, hess = 0;
  };
  Errors size;
  const auto errors = [&](double h) {
    OccupancyField<2> table = exact;
    table.Tabulate(h);
    EXPECT_EQ(table.table_spacing(), h);
    Errors e;
    for (const Vec<2>& s : points) {
      OccupancyValue<2> a, b;
      exact.Evaluate(s, ws.get(), true, &a);
      table.Evaluate(s, ws.get(), true, &b);
      e.p = std::max(e.p, std::abs(a.p - b.p));
      e.grad = std::max(e.grad, (a.gradient - b.gradient).norm());
      e.hess = std::max(e.hess, (a.hessian - b.hessian).norm());
      EXPECT_EQ(table.Probability(s, ws.get()), b.p);
      EXPECT_TRUE(testing::MatricesNear(b.hessian, b.hessian.transpose(), 1e-12));
      size.p = std::max(size.p, a.p);
      size.grad = std::max(size.grad, a.gradient.norm());
      size.hess = std::max(size.hess, a.hessian.norm());
    }
    return e;
  };
  const Errors coarse = errors(sigma / 8), fine = errors(sigma / 16);
  EXPECT_GT(coarse.p / fine.p, 16 * 0.6);
  EXPECT_GT(coarse.grad / fine.grad, 8 * 0.6);
  EXPECT_GT(coarse.hess / fine.hess, 4 * 0.6);
  EXPECT_LT(fine.p, 1e-5 * size.p);
  EXPECT_LT(fine.grad, 1e-3 * size.grad);
  EXPECT_LT(fine.hess, 3e-2 * size.hess);
  // Outside the support the table is not read: the exact field's value there (bias only).
  OccupancyField<2> table = exact;
  table.Tabulate(sigma / 8);
  OccupancyValue<2> out;
  table.Evaluate(Vec<2>(5, 5), ws.get(), true, &out);
  EXPECT_DOUBLE_EQ(out.p, 1 / (1 + std::exp(0.3)));
  EXPECT_EQ(out.gradient.norm(), 0.0);
  // Spacing 0 removes the table.
  table.Tabulate(0);
  EXPECT_EQ(table.table_spacing(), 0.0);
  OccupancyValue<2> a, b;
  table.Evaluate(points[0], ws.get(), true, &a);
  exact.Evaluate(points[0], ws.get(), true, &b);
  EXPECT_EQ(a.p, b.p);
}

// At the nodes the table returns the exact logit and gradient; across a cell edge p and grad p are
// continuous (C1), and the Hessian is that of the interpolant (finite differences of its gradient).
TEST(OccupancyFieldTable, ExactAtTheNodesContinuousAcrossCellsAndItsOwnDerivatives) {
  const RbfGrid<2> grid(SmoothGrid<2>());
  std::mt19937_64 rng(12);
  const OccupancyField<2> exact = RandomField(grid, 1.5, &rng);
  OccupancyField<2> table = exact;
  const double h = 0.02;
  table.Tabulate(h);
  auto ws = exact.MakeWorkspace();
  // The table's nodes sit at lower - cutoff + h (i, j).
  const Vec<2> origin = grid.spec().lower.array() - grid.spec().cutoff_radius;
  for (const auto& [i, j] : {std::pair{40, 50}, std::pair{61, 47}, std::pair{55, 55}}) {
    const Vec<2> node = origin + h * Vec<2>(i, j);
    OccupancyValue<2> a, b;
    exact.Evaluate(node, ws.get(), false, &a);
    table.Evaluate(node, ws.get(), false, &b);
    EXPECT_NEAR(a.p, b.p, 1e-14);
    EXPECT_TRUE(testing::MatricesNear(a.gradient, b.gradient, 1e-12));
    // Either side of the cell edge x = node_x.
    OccupancyValue<2> left, right;
    const Vec<2> edge = node + Vec<2>(0, 0.37 * h);
    table.Evaluate(edge - Vec<2>(1e-9, 0), ws.get(), false, &left);
    table.Evaluate(edge + Vec<2>(1e-9, 0), ws.get(), false, &right);
    // p changes by its slope over the 2e-9 between the two points, nothing more (no jump).
    EXPECT_NEAR(right.p - left.p, 2e-9 * left.gradient[0], 1e-13);
    EXPECT_TRUE(
        testing::MatricesNear(left.gradient, right.gradient, 1e-6 * (1 + left.gradient.norm())));
  }
  for (int n = 0; n < 20; ++n) {
    const Vec<2> s = RandomPoint<2>(&rng, -0.15, 0.15);
    OccupancyValue<2> v, plus, minus;
    table.Evaluate(s, ws.get(), true, &v);
    Mat<2> hess_fd;
    Vec<2> grad_fd;
    const double d = 1e-6;
    for (int a = 0; a < 2; ++a) {
      Vec<2> e = Vec<2>::Zero();
      e[a] = d;
      table.Evaluate(s + e, ws.get(), false, &plus);
      table.Evaluate(s - e, ws.get(), false, &minus);
      grad_fd[a] = (plus.p - minus.p) / (2 * d);
      hess_fd.col(a) = (plus.gradient - minus.gradient) / (2 * d);
    }
    EXPECT_TRUE(testing::MatricesNear(v.gradient, grad_fd, 1e-7 * (1 + v.gradient.norm())));
    EXPECT_TRUE(testing::MatricesNear(v.hessian, hess_fd, 1e-5 * (1 + v.hessian.norm())));
  }
}

TEST(OccupancyFieldTable, BadInputIsAnError) {
  const RbfGrid<2> grid(SmoothGrid<2>());
  OccupancyField<2> field(grid, Eigen::VectorXd::Zero(grid.size()), 0, "obstacle map");
  testing::ExpectErrorContains([&] { field.Tabulate(-0.1, "obstacle map"); },
                               {"obstacle map", "spacing -0.1"});
  testing::ExpectErrorContains([&] { field.Tabulate(std::nan(""), "obstacle map"); },
                               {"obstacle map", "spacing"});
  testing::ExpectErrorContains([&] { field.Tabulate(1e-5, "obstacle map"); },
                               {"obstacle map", "2^22"});
  const RbfGrid<3> grid3(SmoothGrid<3>());
  OccupancyField<3> field3(grid3, Eigen::VectorXd::Zero(grid3.size()), 0);
  testing::ExpectErrorContains([&] { field3.Tabulate(0.01, "arm map"); }, {"arm map", "2-D"});
  EXPECT_NO_THROW(field3.Tabulate(0));
}

// ---- occupancy fit ----------------------------------------------------------------------------

template <int D>
void CheckFitRecoversBall(const Vec<D>& centre, double radius, double box, double sample_spacing,
                          const RbfGridSpec<D>& grid_spec, std::uint64_t seed) {
  const auto sdf = [&](const Vec<D>& s) { return (s - centre).norm() - radius; };
  Eigen::Matrix<double, D, Eigen::Dynamic> points;
  std::vector<std::uint8_t> occupied;
  SampleObstacleOccupancy<D>(sdf, Vec<D>::Constant(-box), Vec<D>::Constant(box), sample_spacing,
                             &points, &occupied);
  const long per_axis = std::lround(2 * box / sample_spacing) + 1;
  ASSERT_EQ(points.cols(), static_cast<long>(std::pow(per_axis, D)));
  for (Eigen::Index i = 0; i < points.cols(); i += 37)
    EXPECT_EQ(occupied[static_cast<std::size_t>(i)], sdf(points.col(i)) <= 0 ? 1 : 0);
  const RbfGrid<D> grid(grid_spec);
  const OccupancyField<D> field = FitOccupancyField<D>(grid, points, occupied, 0.1, "ball");
  auto ws = field.MakeWorkspace();
  // Held-out points: uniform in the box.
  std::mt19937_64 rng(seed);
  int correct = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const Vec<D> s = RandomPoint<D>(&rng, -box, box);
    correct += (field.Probability(s, ws.get()) > 0.5) == (sdf(s) <= 0);
  }
  EXPECT_GT(static_cast<double>(correct) / n, 0.97);
  EXPECT_GT(field.Probability(centre, ws.get()), 0.5);
  for (int a = 0; a < D; ++a)
    for (double sign : {-1.0, 1.0}) {
      Vec<D> far = centre;
      far[a] += sign * 2 * radius;
      EXPECT_LT(field.Probability(far, ws.get()), 0.1) << far.transpose();
    }
}

TEST(FitOccupancyField, RecoversADisc) {
  const RbfGridSpec<2> g = RbfGrid<2>::Covering(Vec<2>(-1, -1), Vec<2>(1, 1), 0.2, 0.1, 120, 0.4);
  CheckFitRecoversBall<2>(Vec<2>(0.2, -0.1), 0.3, 1.0, 0.04, g, 4);
}

TEST(FitOccupancyField, RecoversASphere) {
  const RbfGridSpec<3> g =
      RbfGrid<3>::Covering(Vec<3>::Constant(-0.6), Vec<3>::Constant(0.6), 0.2, 0.2, 40, 0.5);
  CheckFitRecoversBall<3>(Vec<3>(0.05, 0, -0.05), 0.25, 0.6, 0.1, g, 5);
}

TEST(FitOccupancyField, BadInputIsAnError) {
  const RbfGrid<2> grid(RbfGrid<2>::Covering(Vec<2>(-1, -1), Vec<2>(1, 1), 0, 0.1, 120, 0.4));
  Eigen::Matrix<double, 2, -1> pts = Eigen::Matrix<double, 2, -1>::Random(2, 10);
  std::vector<std::uint8_t> labels(10, 1);
  testing::ExpectErrorContains([&] { FitOccupancyField<2>(grid, pts, labels, 0.1, "scan 7"); },
                               {"scan 7", "one class"});
  labels[3] = 0;
  testing::ExpectErrorContains(
      [&] { FitOccupancyField<2>(grid, pts, std::vector<std::uint8_t>(9, 1), 0.1, "scan 7"); },
      {"scan 7", "10 points", "9"});
  pts(1, 4) = std::nan("");
  testing::ExpectErrorContains([&] { FitOccupancyField<2>(grid, pts, labels, 0.1, "scan 7"); },
                               {"scan 7", "not finite"});
  pts(1, 4) = 0;
  testing::ExpectErrorContains([&] { FitOccupancyField<2>(grid, pts, labels, 0, "scan 7"); },
                               {"l2"});
  Eigen::Matrix<double, 2, -1> far = pts.array() + 100.0;
  testing::ExpectErrorContains([&] { FitOccupancyField<2>(grid, far, labels, 0.1, "scan 7"); },
                               {"cut-off"});
  Eigen::Matrix<double, 2, -1> samples;
  std::vector<std::uint8_t> occ;
  testing::ExpectErrorContains(
      [&] {
        SampleObstacleOccupancy<2>([](const Vec<2>&) { return 0.0; }, Vec<2>(0, 0), Vec<2>(1, -1),
                                   0.1, &samples, &occ);
      },
      {"box"});
}

}  // namespace
}  // namespace foresight::imitation
