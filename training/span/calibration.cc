#include "training/span/calibration.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/matrix_normal.h"

namespace foresight::span {

std::vector<PointTerms> CovarianceScaleTerms(const Predictor& model, const WindowSet& windows) {
  FS_THROW_UNLESS(model.observed() == windows.observed,
                  "covariance calibration: the model observes ", model.observed(),
                  " points, the windows have ", windows.observed);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  const double unscale = 1.0 / model.covariance_scale();
  const int R = model.layout().components;
  std::vector<PointTerms> terms;
  terms.reserve(static_cast<std::size_t>(windows.size()) *
                static_cast<std::size_t>(windows.predicted));
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(windows.observed, 2);
  Eigen::Vector2d mean;
  Eigen::Matrix2d cov;
  for (int n = 0; n < windows.size(); ++n) {
    for (int i = 0; i < windows.observed; ++i) past.row(i) = windows.Past(n, i).transpose();
    model.Predict(past, &ws, &dist);
    for (int k = 0; k < windows.predicted; ++k) {
      const double t = (k + 1) * windows.seconds_per_step;
      PointTerms point(static_cast<std::size_t>(R));
      for (int r = 0; r < R; ++r) {
        dist.Position(t, r, &mean, &cov);
        cov *= unscale;
        point[static_cast<std::size_t>(r)] = {
            std::log(dist.alpha(r)) - 0.5 * std::log(cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(1, 0)),
            SquaredMahalanobis2(windows.Future(n, k), mean, cov)};
      }
      terms.push_back(std::move(point));
    }
  }
  return terms;
}

double ScaledNll(const std::vector<PointTerms>& terms, double c) {
  const double log_c = std::log(c), log_2pi = std::log(2.0 * M_PI);
  double sum = 0;
  for (const PointTerms& point : terms) {
    double top = -INFINITY;
    for (const ScaleTerm& s : point) top = std::max(top, s.log_weight - 0.5 * s.d2 / c);
    double acc = 0;
    for (const ScaleTerm& s : point) acc += std::exp(s.log_weight - 0.5 * s.d2 / c - top);
    sum -= top + std::log(acc) - log_2pi - log_c;
  }
  return sum / static_cast<double>(terms.size());
}

double FitCovarianceScale(const std::vector<PointTerms>& terms) {
  FS_THROW_UNLESS(!terms.empty(), "covariance calibration: no validation points to fit on");
  const auto f = [&](double log_c) { return ScaledNll(terms, std::exp(log_c)); };
  const double kLo = -3 * std::log(10.0), kHi = 3 * std::log(10.0);
  constexpr int kGrid = 121;  // log10 c in steps of 0.05
  const double step = (kHi - kLo) / (kGrid - 1);
  int best = 0;
  double best_f = INFINITY;
  for (int i = 0; i < kGrid; ++i) {
    const double v = f(kLo + i * step);
    if (v < best_f) {
      best_f = v;
      best = i;
    }
  }
  // Golden-section search on the bracket of grid neighbours around the best grid point.
  double a = kLo + std::max(best - 1, 0) * step, b = kLo + std::min(best + 1, kGrid - 1) * step;
  const double g = (std::sqrt(5.0) - 1) / 2;
  double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < 60 && b - a > 1e-10; ++it) {
    if (f1 < f2) {  // the minimum lies in [a, x2]
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = f(x1);
    } else {  // in [x1, b]
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = f(x2);
    }
  }
  return std::exp(0.5 * (a + b));
}

}  // namespace foresight::span
