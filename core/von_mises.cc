#include "core/von_mises.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/portable_random.h"

namespace foresight {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kLogTwoPi = 1.8378770664093454836;  // log(2 pi)
/// Below this kappa the power series is summed; above it the asymptotic (Hankel) expansion. At
/// kappa = 30 the smallest asymptotic term is ~1e-25 relative and the series has no cancellation
/// (all terms positive) and no overflow (I0(30) ~ 8e11), so both are accurate to rounding.
constexpr double kSeriesLimit = 30.0;
/// Kappa that InverseA1 returns for R >= 1 - 1e-12 (A1(kappa) ~ 1 - 1/(2 kappa)).
constexpr double kMaxKappa = 5e11;
/// Above this kappa the sampler uses the normal approximation theta - mu ~ N(0, 1/kappa) (its
/// error is O(1/kappa) in the moments; Best-Fisher's rejection constants lose precision there).
constexpr double kNormalSamplerKappa = 1e6;

/// Power series sums, both multiplied by exp(-kappa) (kappa <= kSeriesLimit):
///   I0(k) = sum_j (k^2/4)^j / (j!)^2,   I1(k) = (k/2) sum_j (k^2/4)^j / (j! (j+1)!).
void SeriesScaled(double kappa, double* i0e, double* i1e) {
  const double q = 0.25 * kappa * kappa;
  double t0 = 1.0, s0 = 1.0;  // term and sum of I0
  double t1 = 1.0, s1 = 1.0;  // of I1 / (k/2)
  for (int j = 1; j < 500; ++j) {
    t0 *= q / (static_cast<double>(j) * j);
    t1 *= q / (static_cast<double>(j) * (j + 1));
    s0 += t0;
    s1 += t1;
    if (t0 < 1e-17 * s0 && t1 < 1e-17 * s1) break;
  }
  const double scale = std::exp(-kappa);
  *i0e = s0 * scale;
  *i1e = 0.5 * kappa * s1 * scale;
}

/// Asymptotic expansion (Abramowitz and Stegun 9.7.1) without the factor exp(k) / sqrt(2 pi k):
///   I_nu(k) ~ e^k / sqrt(2 pi k) sum_m c_m,  c_m = c_{m-1} (-(4 nu^2 - (2m-1)^2)) / (8 m k).
/// Summed while the terms decrease (kappa > kSeriesLimit: stops far below double rounding).
double AsymptoticSum(double nu, double kappa) {
  const double mu4 = 4.0 * nu * nu;
  double term = 1.0, sum = 1.0;
  for (int m = 1; m < 60; ++m) {
    const double odd = 2.0 * m - 1.0;
    const double next = term * (-(mu4 - odd * odd)) / (8.0 * m * kappa);
    if (std::abs(next) >= std::abs(term)) break;
    term = next;
    sum += term;
    if (std::abs(term) < 1e-17 * std::abs(sum)) break;
  }
  return sum;
}

void CheckKappa(double kappa, const char* where) {
  FS_THROW_UNLESS(kappa >= 0 && !std::isnan(kappa), where, ": kappa ", kappa,
                  " must be a non-negative number");
}

}  // namespace

double WrapAngle(double theta) {
  double w = std::fmod(theta + M_PI, kTwoPi);
  if (w < 0) w += kTwoPi;
  w -= M_PI;
  // fmod rounding can land exactly on +pi (e.g. theta = pi - tiny); keep the half-open range.
  return w >= M_PI ? -M_PI : w;
}

double LogBesselI0Scaled(double kappa) {
  CheckKappa(kappa, "LogBesselI0");
  if (std::isinf(kappa)) return -std::numeric_limits<double>::infinity();
  if (kappa <= kSeriesLimit) {
    double i0e = 0, i1e = 0;
    SeriesScaled(kappa, &i0e, &i1e);
    return std::log(i0e);
  }
  return std::log(AsymptoticSum(0.0, kappa)) - 0.5 * (kLogTwoPi + std::log(kappa));
}

double LogBesselI0(double kappa) { return kappa + LogBesselI0Scaled(kappa); }

double BesselRatioA1(double kappa) {
  CheckKappa(kappa, "BesselRatioA1");
  if (std::isinf(kappa)) return 1.0;
  if (kappa <= kSeriesLimit) {
    double i0e = 0, i1e = 0;
    SeriesScaled(kappa, &i0e, &i1e);
    return i1e / i0e;
  }
  return AsymptoticSum(1.0, kappa) / AsymptoticSum(0.0, kappa);
}

double BesselRatioA1Derivative(double kappa) {
  // d/dk (I1/I0) = I1'/I0 - I1 I0'/I0^2 with I0' = I1 and I1' = I0 - I1/k.
  if (kappa < 1e-8) return 0.5 - 3.0 * kappa * kappa / 16.0;
  const double a = BesselRatioA1(kappa);
  return 1.0 - a / kappa - a * a;
}

double InverseA1(double r) {
  FS_THROW_UNLESS(r >= 0 && r <= 1, "InverseA1: mean resultant length ", r, " is outside [0, 1]");
  if (r == 0) return 0.0;
  if (r >= 1.0 - 1e-12) return kMaxKappa;
  // Initial guess: Best and Fisher (1981) as given in Fisher (1993), "Statistical analysis of
  // circular data", eq. 4.40; Banerjee et al. (2005) k = r (2 - r^2) / (1 - r^2) would do too.
  double k;
  if (r < 0.53) {
    k = 2 * r + r * r * r + 5 * std::pow(r, 5) / 6;
  } else if (r < 0.85) {
    k = -0.4 + 1.39 * r + 0.43 / (1 - r);
  } else {
    k = 1 / (r * r * r - 4 * r * r + 3 * r);
  }
  // Newton on A1(k) = r, safeguarded by a bracket (A1 is increasing; bisect in log space when a
  // step leaves the bracket).
  double lo = 0, hi = kMaxKappa;
  k = std::clamp(k, 1e-300, hi);
  for (int it = 0; it < 200; ++it) {
    const double f = BesselRatioA1(k) - r;
    if (f == 0) break;
    if (f < 0)
      lo = k;
    else
      hi = k;
    const double step = f / BesselRatioA1Derivative(k);
    double next = k - step;
    if (!(next > lo && next < hi)) next = lo > 0 ? std::sqrt(lo * hi) : 0.5 * hi;
    if (std::abs(next - k) <= 1e-15 * k) {
      k = next;
      break;
    }
    k = next;
  }
  return k;
}

double VonMisesLogDensity(double theta, double mu, double kappa) {
  // kappa cos(d) - log(2 pi I0(kappa)) = kappa (cos d - 1) - log(2 pi) - (log I0(kappa) - kappa);
  // cos d - 1 = -2 sin^2(d / 2) keeps precision for large kappa near the mode.
  const double s = std::sin(0.5 * (theta - mu));
  return -2.0 * kappa * s * s - kLogTwoPi - LogBesselI0Scaled(kappa);
}

double VonMisesMixtureLogDensity(double theta, const Eigen::Ref<const Eigen::VectorXd>& alpha,
                                 const Eigen::Ref<const Eigen::VectorXd>& mu,
                                 const Eigen::Ref<const Eigen::VectorXd>& kappa) {
  FS_THROW_UNLESS(alpha.size() == mu.size() && alpha.size() == kappa.size() && alpha.size() > 0,
                  "VonMisesMixtureLogDensity: alpha [", alpha.size(), "], mu [", mu.size(),
                  "] and kappa [", kappa.size(), "] must have the same positive size");
  // log sum_r alpha_r p_r(theta), by log-sum-exp; components with alpha_r = 0 are absent.
  double m = -std::numeric_limits<double>::infinity();
  for (Eigen::Index r = 0; r < alpha.size(); ++r) {
    if (alpha[r] <= 0) continue;
    m = std::max(m, std::log(alpha[r]) + VonMisesLogDensity(theta, mu[r], kappa[r]));
  }
  if (!std::isfinite(m)) return m;
  double s = 0;
  for (Eigen::Index r = 0; r < alpha.size(); ++r) {
    if (alpha[r] <= 0) continue;
    s += std::exp(std::log(alpha[r]) + VonMisesLogDensity(theta, mu[r], kappa[r]) - m);
  }
  return m + std::log(s);
}

double SampleVonMises(double mu, double kappa, std::mt19937_64* rng) {
  CheckKappa(kappa, "SampleVonMises");
  if (kappa < 1e-8) return WrapAngle(kTwoPi * Uniform01(rng));
  if (kappa > kNormalSamplerKappa) {
    // Box-Muller: theta - mu ~ N(0, 1 / kappa).
    const double u1 = 1.0 - Uniform01(rng), u2 = Uniform01(rng);
    const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
    return WrapAngle(mu + z / std::sqrt(kappa));
  }
  // Best and Fisher (1979), "Efficient simulation of the von Mises distribution", Appl. Stat. 28.
  const double tau = 1.0 + std::sqrt(1.0 + 4.0 * kappa * kappa);
  const double rho = (tau - std::sqrt(2.0 * tau)) / (2.0 * kappa);
  const double r = (1.0 + rho * rho) / (2.0 * rho);
  double f = 0;
  for (;;) {
    const double u1 = Uniform01(rng), u2 = Uniform01(rng);
    const double z = std::cos(M_PI * u1);
    f = (1.0 + r * z) / (r + z);
    const double c = kappa * (r - f);
    if (c * (2.0 - c) - u2 > 0) break;
    if (u2 > 0 && std::log(c / u2) + 1.0 - c >= 0) break;
  }
  const double u3 = Uniform01(rng);
  const double angle = std::acos(std::clamp(f, -1.0, 1.0));
  return WrapAngle(u3 < 0.5 ? mu - angle : mu + angle);
}

VonMisesFit FitVonMises(const Eigen::Ref<const Eigen::VectorXd>& theta,
                        const Eigen::Ref<const Eigen::VectorXd>& weight) {
  FS_THROW_UNLESS(theta.size() == weight.size() && theta.size() > 0, "FitVonMises: theta [",
                  theta.size(), "] and weight [", weight.size(),
                  "] must have the same positive size");
  double c = 0, s = 0, w = 0;
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    FS_THROW_UNLESS(weight[i] >= 0 && std::isfinite(weight[i]), "FitVonMises: weight ", i, " is ",
                    weight[i], " (must be finite and >= 0)");
    FS_THROW_UNLESS(std::isfinite(theta[i]), "FitVonMises: theta ", i, " is ", theta[i]);
    c += weight[i] * std::cos(theta[i]);
    s += weight[i] * std::sin(theta[i]);
    w += weight[i];
  }
  FS_THROW_UNLESS(w > 0, "FitVonMises: the weights sum to ", w, " (must be positive)");
  // ML: mu = atan2(S, C); A1(kappa) = R = |(C, S)| / sum w (Mardia and Jupp 2000, sec. 5.3).
  VonMisesFit fit;
  fit.mu = WrapAngle(std::atan2(s, c));
  fit.kappa = InverseA1(std::min(1.0, std::hypot(c, s) / w));
  return fit;
}

namespace {
void CheckBatch(const VonMisesMixtureBatch& m, const Eigen::Ref<const Eigen::VectorXd>& theta,
                const char* what) {
  FS_THROW_UNLESS(m.alpha.rows() == theta.size() && m.mu.rows() == theta.size() &&
                      m.kappa.rows() == theta.size() && m.alpha.cols() == m.mu.cols() &&
                      m.alpha.cols() == m.kappa.cols() && m.alpha.cols() > 0,
                  what, ": mixtures alpha [", m.alpha.rows(), " x ", m.alpha.cols(), "], mu [",
                  m.mu.rows(), " x ", m.mu.cols(), "], kappa [", m.kappa.rows(), " x ",
                  m.kappa.cols(), "] do not match ", theta.size(), " headings");
  FS_THROW_UNLESS(theta.size() > 0, what, ": no headings");
}
}  // namespace

double AverageLikelihood(const VonMisesMixtureBatch& mixtures,
                         const Eigen::Ref<const Eigen::VectorXd>& theta) {
  CheckBatch(mixtures, theta, "AverageLikelihood");
  // Thesis ch 4 "Average Likelihood": AL = 1/N' sum_n sum_r alpha_r VM(theta_n; mu_r, kappa_r).
  double sum = 0;
  for (Eigen::Index n = 0; n < theta.size(); ++n) {
    sum += std::exp(VonMisesMixtureLogDensity(theta[n], mixtures.alpha.row(n).transpose(),
                                              mixtures.mu.row(n).transpose(),
                                              mixtures.kappa.row(n).transpose()));
  }
  return sum / static_cast<double>(theta.size());
}

double MinimumRotationError(const VonMisesMixtureBatch& mixtures,
                            const Eigen::Ref<const Eigen::VectorXd>& theta) {
  return MinimumRotationError(mixtures, theta, 0.0);
}

double MinimumRotationError(const VonMisesMixtureBatch& mixtures,
                            const Eigen::Ref<const Eigen::VectorXd>& theta, double min_weight) {
  CheckBatch(mixtures, theta, "MinimumRotationError");
  FS_THROW_UNLESS(min_weight >= 0 && min_weight <= 1, "MinimumRotationError: min_weight ",
                  min_weight, " must be in [0, 1]");
  // Thesis ch 4 "Minimum Rotation Error" (thesis.tex near line 1285) prints
  //   MRE = 1/N' sum_n min_r |theta_n - mu_r|,
  // which is wrong on the circle (theta = pi - 0.01 and mu = -pi + 0.01 are 0.02 rad apart, not
  // 6.26). We use the wrapped difference |wrap(theta_n - mu_r)| in [0, pi]. Components with
  // alpha_r = 0 (padding of a smaller mixture) are not part of the mixture and are skipped.
  double sum = 0;
  for (Eigen::Index n = 0; n < theta.size(); ++n) {
    double best = std::numeric_limits<double>::infinity();
    Eigen::Index heaviest = 0;  // the first of the largest alphas always counts
    for (Eigen::Index r = 1; r < mixtures.alpha.cols(); ++r)
      if (mixtures.alpha(n, r) > mixtures.alpha(n, heaviest)) heaviest = r;
    for (Eigen::Index r = 0; r < mixtures.mu.cols(); ++r) {
      if (mixtures.alpha(n, r) <= 0) continue;
      if (mixtures.alpha(n, r) < min_weight && r != heaviest) continue;
      best = std::min(best, std::abs(WrapAngle(theta[n] - mixtures.mu(n, r))));
    }
    FS_THROW_UNLESS(std::isfinite(best), "MinimumRotationError: mixture ", n,
                    " has no component with positive alpha");
    sum += best;
  }
  return sum / static_cast<double>(theta.size());
}

void CapConcentration(VonMisesMixtureBatch* mixtures, double cap) {
  FS_THROW_UNLESS(mixtures != nullptr, "CapConcentration: no mixtures");
  FS_THROW_UNLESS(cap > 0, "CapConcentration: cap ", cap, " must be > 0");
  Eigen::MatrixXd& kappa = mixtures->kappa;
  for (Eigen::Index j = 0; j < kappa.cols(); ++j)
    for (Eigen::Index i = 0; i < kappa.rows(); ++i)
      if (kappa(i, j) > cap) kappa(i, j) = cap;
}

}  // namespace foresight
