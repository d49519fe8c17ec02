#pragma once
/// Random directional maps for engine tests (no LibTorch needed).

#include <random>
#include <string>

#include "core/h5.h"
#include "inference/directional/directional_map.h"
#include "inference/engine/artifact.h"

namespace foresight::testing {

inline DirectionalFeatureConfig SmallFeatureConfig() {
  DirectionalFeatureConfig f;
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
inline DirectionalMap RandomDirectionalMap(DirectionalVariant v, const DirectionalFeatureConfig& f, int hidden,
                                           int components, std::uint64_t seed, float scale = 0.5f,
                                           double max_kappa = kDirectionalDefaultMaxKappa) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> n(0.0f, scale);
  auto mat = [&](long r, long c) { return Eigen::MatrixXf(Eigen::MatrixXf::NullaryExpr(r, c, [&] { return n(rng); })); };
  auto vec = [&](long r) { return Eigen::VectorXf(Eigen::VectorXf::NullaryExpr(r, [&] { return n(rng); })); };
  const int ms = f.cells_x * f.cells_y;
  Lstm lstm;
  int d = ms;
  if (v == DirectionalVariant::kSpatiotemporal) {
    lstm = Lstm(LstmWeights{mat(4 * hidden, ms), mat(4 * hidden, hidden), vec(4 * hidden), vec(4 * hidden)});
    d = hidden;
  }
  DirectionalHeads h{mat(components, d), mat(components, d), mat(components, d), vec(components), vec(components),
                     vec(components)};
  return DirectionalMap(v, f, std::move(lstm), std::move(h), max_kappa);
}

/// Writes `map` as a directional_map artifact (the schema of docs/artifact_schema.md).
inline void WriteDirectionalArtifact(const DirectionalMap& map, const std::string& path) {
  h5::File f = h5::File::Create(path);
  Artifact::WriteHeader(&f, kDirectionalModelType, "model: directional\n", 0);
  const DirectionalFeatureConfig& c = map.features().config();
  f.SetAttr("/model", "variant", std::string(VariantName(map.variant())));
  f.SetAttr("/model", "components", static_cast<std::int64_t>(map.components()));
  f.SetAttr("/model", "log_kappa_max", std::log(map.max_kappa()));
  const std::string g = "/model/features";
  f.SetAttr(g, "x_min", c.x_min);
  f.SetAttr(g, "x_max", c.x_max);
  f.SetAttr(g, "y_min", c.y_min);
  f.SetAttr(g, "y_max", c.y_max);
  f.SetAttr(g, "cells_x", static_cast<std::int64_t>(c.cells_x));
  f.SetAttr(g, "cells_y", static_cast<std::int64_t>(c.cells_y));
  f.SetAttr(g, "length_scale", c.length_scale);
  f.SetAttr(g, "t_min", c.t_min);
  f.SetAttr(g, "t_max", c.t_max);
  f.SetAttr(g, "time_points", static_cast<std::int64_t>(c.time_points));
  f.SetAttr(g, "time_length_scale", c.time_length_scale);
  f.SetAttr(g, "cutoff", c.cutoff);
  if (map.variant() == DirectionalVariant::kSpatiotemporal) {
    const LstmWeights& w = map.lstm().weights();
    f.WriteMatrix("/weights/lstm/weight_ih_l0", w.weight_ih);
    f.WriteMatrix("/weights/lstm/weight_hh_l0", w.weight_hh);
    f.WriteMatrix("/weights/lstm/bias_ih_l0", Eigen::MatrixXf(w.bias_ih));
    f.WriteMatrix("/weights/lstm/bias_hh_l0", Eigen::MatrixXf(w.bias_hh));
  }
  const DirectionalHeads& h = map.heads();
  f.WriteMatrix("/weights/alpha/weight", h.alpha_w);
  f.WriteMatrix("/weights/alpha/bias", Eigen::MatrixXf(h.alpha_b));
  f.WriteMatrix("/weights/mu/weight", h.mu_w);
  f.WriteMatrix("/weights/mu/bias", Eigen::MatrixXf(h.mu_b));
  f.WriteMatrix("/weights/kappa/weight", h.kappa_w);
  f.WriteMatrix("/weights/kappa/bias", Eigen::MatrixXf(h.kappa_b));
}

}  // namespace foresight::testing
