#pragma once
/// Independent reference computations for the occupancy-map tests: dense hinge features by brute
/// force over every inducing point (no HingeGrid involved), random Fast-BHM / BHM / Hilbert
/// weights, and small labelled point sets. Header-only; torch-free.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/hinge_grid.h"
#include "inference/mapping/hinge_map.h"

namespace foresight::testing {

/// A small hinge grid from the origin to (x_max, y_max) every 0.5 m.
inline HingeGridConfig SmallGrid(double x_max, double y_max, double gamma, double cutoff_radius) {
  HingeGridConfig c;
  c.x_min = 0;
  c.x_max = x_max;
  c.y_min = 0;
  c.y_max = y_max;
  c.spacing = 0.5;
  c.gamma = gamma;
  c.cutoff_radius = cutoff_radius;
  return c;
}

/// Inducing points per axis as the config documents it: round((max - min) / spacing), at least 1.
inline int InducingCount(double min, double max, double spacing) {
  return std::max(1, static_cast<int>(std::lround((max - min) / spacing)));
}

/// Centre of feature t = iy * nx + ix straight from the config.
inline Eigen::Vector2d ReferenceCentre(const HingeGridConfig& c, int t) {
  const int nx = InducingCount(c.x_min, c.x_max, c.spacing);
  return {c.x_min + (t % nx) * c.spacing, c.y_min + (t / nx) * c.spacing};
}

inline int ReferenceSize(const HingeGridConfig& c) {
  return InducingCount(c.x_min, c.x_max, c.spacing) * InducingCount(c.y_min, c.y_max, c.spacing);
}

/// Dense feature vector [T]: exp(-gamma d^2) for every centre within the cut-off, else 0.
inline Eigen::VectorXd DenseFeatures(const HingeGridConfig& c, double x, double y) {
  const int t_size = ReferenceSize(c);
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(t_size);
  for (int t = 0; t < t_size; ++t) {
    const Eigen::Vector2d ctr = ReferenceCentre(c, t);
    const double d2 = (x - ctr.x()) * (x - ctr.x()) + (y - ctr.y()) * (y - ctr.y());
    if (d2 <= c.cutoff_radius * c.cutoff_radius) phi[t] = std::exp(-c.gamma * d2);
  }
  return phi;
}

/// Dense design matrix [n x T] of the points xy [2 x n].
inline Eigen::MatrixXd DenseDesign(const HingeGridConfig& c, const Eigen::Matrix2Xd& xy) {
  Eigen::MatrixXd phi(xy.cols(), ReferenceSize(c));
  for (Eigen::Index n = 0; n < xy.cols(); ++n)
    phi.row(n) = DenseFeatures(c, xy(0, n), xy(1, n)).transpose();
  return phi;
}

/// Distance of (x, y) to the nearest cut-off circle: small values mean a feature switches on or off
/// nearby (the features are discontinuous there, so finite differences must stay away).
inline double DistanceToCutoff(const HingeGridConfig& c, double x, double y) {
  double best = 1e300;
  for (int t = 0; t < ReferenceSize(c); ++t) {
    const Eigen::Vector2d ctr = ReferenceCentre(c, t);
    best = std::min(best, std::abs(std::hypot(x - ctr.x(), y - ctr.y()) - c.cutoff_radius));
  }
  return best;
}

inline double ReferenceSigmoid(double a) { return 1.0 / (1.0 + std::exp(-a)); }

/// Random weights of the given kind on `grid`: means N(0, 1.5^2), variances in [0.05, 2], and for
/// BHMs a dense SPD covariance with correlated neighbours.
inline occupancy::HingeMap RandomHingeMap(occupancy::HingeMapKind kind, const HingeGrid& grid,
                                          std::uint64_t seed, double prior_mean = 0.0,
                                          double prior_variance = 10.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> u(0.05, 2.0);
  const int t_size = grid.size();
  occupancy::HingeWeights w;
  w.mean.resize(t_size);
  for (int t = 0; t < t_size; ++t) w.mean[t] = 1.5 * n01(rng);
  if (kind == occupancy::HingeMapKind::kFastBhm) {
    w.variance.resize(t_size);
    for (int t = 0; t < t_size; ++t) w.variance[t] = u(rng);
  } else if (kind == occupancy::HingeMapKind::kBhm) {
    Eigen::MatrixXd a(t_size, t_size);
    for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = n01(rng);
    w.covariance = a * a.transpose() / t_size + 0.1 * Eigen::MatrixXd::Identity(t_size, t_size);
  }
  return occupancy::HingeMap(kind, grid, std::move(w), prior_mean, prior_variance);
}

/// Points of one "scan": n points uniform in [x0, x1] x [y0, y1] with random labels.
struct PointSet {
  Eigen::Matrix2Xd xy;
  std::vector<std::uint8_t> occupied;
};
inline PointSet RandomPoints(int n, double x0, double x1, double y0, double y1,
                             std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(x0, x1), uy(y0, y1);
  std::bernoulli_distribution b(0.4);
  PointSet p;
  p.xy.resize(2, n);
  p.occupied.resize(n);
  for (int i = 0; i < n; ++i) {
    p.xy(0, i) = ux(rng);
    p.xy(1, i) = uy(rng);
    p.occupied[i] = b(rng) ? 1 : 0;
  }
  return p;
}
inline PointSet Concat(const PointSet& a, const PointSet& b) {
  PointSet p;
  p.xy.resize(2, a.xy.cols() + b.xy.cols());
  p.xy << a.xy, b.xy;
  p.occupied = a.occupied;
  p.occupied.insert(p.occupied.end(), b.occupied.begin(), b.occupied.end());
  return p;
}

}  // namespace foresight::testing
