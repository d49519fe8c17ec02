#include "inference/constrained/gauss_hermite.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "core/error.h"

namespace foresight::constrained {

namespace {

// Orthonormal Hermite polynomial p_n(x) (w.r.t. exp(-x^2)) and p_{n-1}(x) by the three-term
// recurrence; the orthonormal form stays finite for n <= 64 where H_n itself would be huge.
void Hermite(int n, double x, double* p_n, double* p_prev) {
  double p0 = std::pow(M_PI, -0.25), p1 = 0;
  for (int j = 1; j <= n; ++j) {
    const double p2 = p1;
    p1 = p0;
    p0 = x * std::sqrt(2.0 / j) * p1 - std::sqrt((j - 1.0) / j) * p2;
  }
  *p_n = p0;
  *p_prev = p1;
}

}  // namespace

GaussHermiteRule GaussHermite(int n) {
  FS_THROW_UNLESS(n >= 1 && n <= 64, "GaussHermite: number of nodes n must be in [1, 64], got ", n);
  // Golub-Welsch: the nodes are the eigenvalues of the symmetric Jacobi matrix of the Hermite
  // recurrence (off-diagonal sqrt(k / 2)).
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) jacobi(k, k - 1) = jacobi(k - 1, k) = std::sqrt(0.5 * k);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(jacobi);
  FS_THROW_UNLESS(eig.info() == Eigen::Success,
                  "GaussHermite: eigen-decomposition failed for n = ", n);
  GaussHermiteRule rule;
  rule.nodes = eig.eigenvalues();  // ascending
  rule.weights.resize(n);
  for (int i = 0; i < n; ++i) {
    // Two Newton steps on p_n polish the eigenvalue; the weight 2 / p_n'(x)^2 with
    // p_n' = sqrt(2 n) p_{n-1} is more accurate for the tiny outer weights than sqrt(pi) v_0^2.
    double x = rule.nodes[i], pn = 0, pm = 0;
    for (int it = 0; it < 2; ++it) {
      Hermite(n, x, &pn, &pm);
      x -= pn / (std::sqrt(2.0 * n) * pm);
    }
    Hermite(n, x, &pn, &pm);
    const double dp = std::sqrt(2.0 * n) * pm;
    rule.nodes[i] = x;
    rule.weights[i] = 2.0 / (dp * dp);
  }
  // Exact symmetry about 0.
  for (int i = 0; i < n / 2; ++i) {
    const int j = n - 1 - i;
    const double x = 0.5 * (rule.nodes[j] - rule.nodes[i]);
    const double w = 0.5 * (rule.weights[i] + rule.weights[j]);
    rule.nodes[i] = -x;
    rule.nodes[j] = x;
    rule.weights[i] = rule.weights[j] = w;
  }
  if (n % 2 == 1) rule.nodes[n / 2] = 0;
  return rule;
}

StandardNormalRule2 StandardNormalRule(int order) {
  FS_THROW_UNLESS(order >= 1 && order <= 64,
                  "StandardNormalRule: order (points per axis) must be in [1, 64], got ", order);
  const GaussHermiteRule gh = GaussHermite(order);
  StandardNormalRule2 rule;
  rule.points.resize(2, order * order);
  rule.weights.resize(order * order);
  const double root2 = std::sqrt(2.0);
  for (int i = 0; i < order; ++i) {
    for (int j = 0; j < order; ++j) {
      const int q = i * order + j;
      rule.points(0, q) = root2 * gh.nodes[i];
      rule.points(1, q) = root2 * gh.nodes[j];
      rule.weights[q] = gh.weights[i] * gh.weights[j] / M_PI;
    }
  }
  return rule;
}

StandardNormalRule2 PrunedRuleByMass(int order, double max_dropped_mass) {
  FS_THROW_UNLESS(std::isfinite(max_dropped_mass) && max_dropped_mass >= 0 && max_dropped_mass < 1,
                  "PrunedRuleByMass: max_dropped_mass must be in [0, 1), got ", max_dropped_mass);
  const StandardNormalRule2 rule = StandardNormalRule(order);
  // Points in orbits of the square's symmetries: (i, j) with i <-> n - 1 - i, j <-> n - 1 - j and
  // i <-> j share one weight. Orbits go or stay whole, so the kept rule is as symmetric as the
  // full one (zero mean, isotropic covariance). Orbit key: (a, b) = the sorted folded indices.
  const int n = order, half = (n + 1) / 2;
  const auto fold = [n](int i) { return std::min(i, n - 1 - i); };
  std::vector<double> orbit_mass(static_cast<std::size_t>(half * half), 0.0);
  std::vector<int> orbit_of(static_cast<std::size_t>(n * n));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = std::min(fold(i), fold(j)), b = std::max(fold(i), fold(j));
      const int q = i * n + j, o = a * half + b;
      orbit_of[static_cast<std::size_t>(q)] = o;
      orbit_mass[static_cast<std::size_t>(o)] += rule.weights[q];
    }
  // Lightest orbits first by their members' weight (the weight of the orbit's point (a, b)); ties
  // by key, so the result does not depend on the sort.
  std::vector<int> orbits;
  for (int a = 0; a < half; ++a)
    for (int b = a; b < half; ++b) orbits.push_back(a * half + b);
  const auto member = [&](int o) { return rule.weights[(o / half) * n + o % half]; };
  std::sort(orbits.begin(), orbits.end(), [&](int x, int y) {
    return member(x) < member(y) || (member(x) == member(y) && x < y);
  });
  std::vector<char> dropped(orbit_mass.size(), 0);
  double mass = 0;
  for (int o : orbits) {
    if (mass + orbit_mass[static_cast<std::size_t>(o)] > max_dropped_mass) break;
    mass += orbit_mass[static_cast<std::size_t>(o)];
    dropped[static_cast<std::size_t>(o)] = 1;
  }
  int kept = 0;
  for (int q = 0; q < rule.size(); ++q)
    kept += !dropped[static_cast<std::size_t>(orbit_of[static_cast<std::size_t>(q)])];
  StandardNormalRule2 out;
  out.points.resize(2, kept);
  out.weights.resize(kept);
  int k = 0;
  for (int q = 0; q < rule.size(); ++q) {
    if (dropped[static_cast<std::size_t>(orbit_of[static_cast<std::size_t>(q)])]) continue;
    out.points.col(k) = rule.points.col(q);
    out.weights[k++] = rule.weights[q];
  }
  return out;
}

}  // namespace foresight::constrained
