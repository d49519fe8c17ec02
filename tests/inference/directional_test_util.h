#pragma once
/// Random directional maps for engine tests (no LibTorch needed).

#include <random>
#include <string>

#include "core/h5.h"
#include "inference/directional/directional_map.h"
#include "inference/engine/artifact.h"

namespace foresight::testing {

inline directional::FeatureConfig SmallFeatureConfig() {
  directional::FeatureConfig f;
  f.x_min = 0;
  f.x_max = 10;
  f.y_min = -2;
  f.y_max = 6;
  f.cells_x = 5;
  f.cells_y = 4;
  f.length_scale = 1.5;
  f.t_min = 0;
  f.t_max = 60;
  f.time_points = 3;
  f.time_length_scale = 20;
  f.cutoff = 4;
  return f;
}

/// Random LSTM and heads; weights ~ N(0, scale^2).
inline directional::Map RandomDirectionalMap(
    directional::Variant v, const directional::FeatureConfig& f, int hidden, int components,
    std::uint64_t seed, float scale = 0.5f,
    double max_kappa = directional::kDirectionalDefaultMaxKappa) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> n(0.0f, scale);
  auto mat = [&](long r, long c) {
    return Eigen::MatrixXf(Eigen::MatrixXf::NullaryExpr(r, c, [&] { return n(rng); }));
  };
  auto vec = [&](long r) {
    return Eigen::VectorXf(Eigen::VectorXf::NullaryExpr(r, [&] { return n(rng); }));
  };
  const int ms = f.cells_x * f.cells_y;
  Lstm lstm;
  int d = ms;
  if (v == directional::Variant::kSpatiotemporal) {
    lstm = Lstm(LstmWeights{mat(4 * hidden, ms), mat(4 * hidden, hidden), vec(4 * hidden),
                            vec(4 * hidden)});
    d = hidden;
  }
  directional::Heads h{mat(components, d), mat(components, d), mat(components, d),
                       vec(components),    vec(components),    vec(components)};
  return directional::Map(v, f, std::move(lstm), std::move(h), max_kappa);
}

}  // namespace foresight::testing
