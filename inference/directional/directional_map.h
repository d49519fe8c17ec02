#pragma once
/// Continuous spatiotemporal directional map (thesis ch 4): the Eigen engine of an exported
/// `directional_map` artifact (schema: docs/artifact_schema.md).
///
///   spatiotemporal:  phi_s(x) (x) phi_t(t) -> LSTM (sequence over the M_t temporal inducing
///                    points, last hidden state h) -> heads on h,
///   spatial:         phi_s(x) -> heads,
///   heads:           alpha = softmax(W_a z + b_a), mu = W_m z + b_m, kappa = exp(clamp(W_k z +
///   b_k)),
///                    R von Mises components, p(theta | x, y, t) = sum_r alpha_r VM(theta; mu_r,
///                    kappa_r).
///
/// Features (and the behaviour outside the inducing grid and time range) are those of
/// inference/directional/features.h: t is clamped to the time range; positions are not clamped and
/// far from every inducing point the map answers its data-free mixture. Non-finite queries are
/// Errors. Immutable; one Workspace per caller; no allocation once the workspace and the output
/// batch are sized.

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "core/von_mises.h"
#include "inference/directional/features.h"
#include "inference/engine/lstm.h"

namespace foresight::directional {

inline constexpr const char* kModelType = "directional_map";

enum class Variant { kSpatiotemporal, kSpatial };
const char* VariantName(Variant v);

/// log kappa is clamped to [kDirectionalLogKappaMin, log max_kappa] in the head (training and
/// engine alike); max_kappa is a model parameter (artifact attribute log_kappa_max), by default the
/// cap of the directional grid maps (100), so that no method wins AL by spikes on repeated
/// headings.
inline constexpr double kDirectionalLogKappaMin = -10.0;
inline constexpr double kDirectionalDefaultMaxKappa = 100.0;

struct Heads {
  Eigen::MatrixXf alpha_w, mu_w, kappa_w;  ///< [R x D] each
  Eigen::VectorXf alpha_b, mu_b, kappa_b;  ///< [R]
};

class Map {
 public:
  struct Workspace {
    Lstm::Workspace lstm;
    Eigen::VectorXf proj;   ///< [4H] W_ih phi_s
    Eigen::VectorXf phi_s;  ///< [M_s] dense spatial features (spatial variant)
    Eigen::VectorXf phi_t;  ///< [M_t]
    Eigen::VectorXf raw;    ///< [3R] head outputs: logits, means, log kappa (before activations)
    Eigen::VectorXd alpha, mu, kappa;  ///< [R] decoded mixture of the last query
  };

  /// Opens and checks an artifact; a missing file, another model type or inconsistent tensors are
  /// Errors naming the file.
  static Map Load(const std::string& path);
  /// Writes an artifact that Load reads (to path.tmp, then renamed into place); the engine owns
  /// the schema both ways (docs/artifact_schema.md).
  void Save(const std::string& path, const std::string& config_yaml, std::int64_t seed) const;
  /// Builds a map from parts (exporters, tests). `lstm` is ignored for the spatial variant.
  Map(Variant variant, const FeatureConfig& features, Lstm lstm, Heads heads,
      double max_kappa = kDirectionalDefaultMaxKappa);

  Variant variant() const { return variant_; }
  int components() const { return static_cast<int>(heads_.alpha_b.size()); }
  const Features& features() const { return features_; }
  const Lstm& lstm() const { return lstm_; }
  const Heads& heads() const { return heads_; }
  double max_kappa() const { return std::exp(log_kappa_max_); }

  Workspace MakeWorkspace() const;

  /// Head outputs before activations for one query into ws->raw [3R] (parity with LibTorch).
  void RawOutput(double x, double y, double t, Workspace* ws) const;
  /// Mixture at one query into ws->alpha, ws->mu (wrapped to [-pi, pi)), ws->kappa.
  void QueryOne(double x, double y, double t, Workspace* ws) const;
  /// Mixtures at n queries (x, y [m], t [s], each [n]): row i of `out` (resized to n x R; no
  /// allocation when it already has that size).
  void Query(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
             const Eigen::Ref<const Eigen::VectorXd>& t, Workspace* ws,
             VonMisesMixtureBatch* out) const;
  /// Densities p(theta_i | x_i, y_i, t_i) (1/rad) for n queries into `density` [n].
  void Density(const Eigen::Ref<const Eigen::VectorXd>& x,
               const Eigen::Ref<const Eigen::VectorXd>& y,
               const Eigen::Ref<const Eigen::VectorXd>& t,
               const Eigen::Ref<const Eigen::VectorXd>& theta, Workspace* ws,
               Eigen::Ref<Eigen::VectorXd> density) const;

 private:
  Map() = default;
  void Check() const;
  Variant variant_ = Variant::kSpatiotemporal;
  Features features_;
  Lstm lstm_;
  Heads heads_;
  double log_kappa_max_ = std::log(kDirectionalDefaultMaxKappa);
};

}  // namespace foresight::directional
