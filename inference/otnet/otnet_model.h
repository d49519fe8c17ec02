#pragma once
/// The OTNet engine (thesis ch 6), torch-free: encode a new map by its Hausdorff similarities to
/// the database (map_encoding.h), predict the mixture over trajectory weights with the exported
/// MLP, give per-component position distributions at any taus, condition on a start point, sample
/// trajectories and reject those that cross occupied cells.
///
/// Mixture over w = [w_x; w_y] in R^{2M} (thesis eq. NormalAss, mean-field components):
///   p(w | phi) = sum_q alpha_q prod_j p(w_j; mu_qj, s_qj),
/// Normal: p = N(mu, s^2); Laplace: p = exp(-|w - mu| / s) / (2 s), variance 2 s^2.
/// Network head (OtnetHead): Q alpha logits (softmax), Q x 2M means, Q x 2M log-scales clamped to
/// [kLogScaleMin, kLogScaleMax] (exp), in that order, component-major.
///
/// Positions at taus [L]: x = K w_x with K = K(taus) [L x M], so component q has mean K mu_q^x and
/// covariance K Var_q^x K' (full, although Var is diagonal), likewise for y; x and y are
/// independent within a component.
///
/// Start conditioning (thesis eqs. for mu-bar, Sigma-bar): conditioning x(0) = s_x is a linear
/// constraint k0' w_x = s_x with k0 = k(0), so for a Gaussian component the conditional of w_x is
/// exact and rank-one:
///   mu_c = mu + g (s_x - k0' mu),  Var_c = Var - g k0' Var,  g = Var k0 / (k0' Var k0),
/// and its image at taus is the thesis's conditional of positions (tested against it). Samples are
/// drawn as w = mu + s * eps, then w_x += g_x (s_x - k0' w_x) (exact for Normal components; for
/// Laplace components the same correction, i.e. the moment-matched conditional). Components are
/// reweighted by the likelihood of the start, alpha_q N(s; mu_q(0), Sigma_q(0)) normalised
/// (ComponentSelection::kAll) or only the most likely one is kept (kNearest).

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/binary_grid.h"
#include "inference/engine/dense.h"
#include "inference/otnet/map_encoding.h"
#include "inference/otnet/trajectory_basis.h"
#include "inference/otnet/trajectory_metrics.h"

namespace foresight::otnet {

inline constexpr const char* kOtnetModelType = "otnet";

enum class MixtureFamily { kNormal, kLaplace };
const char* ToString(MixtureFamily f);

/// Output layout of the network (shared by the LibTorch net and the engine).
struct OtnetHead {
  int components = 4;  ///< Q
  int weights = 30;    ///< 2M
  static constexpr double kLogScaleMin = -7.0;
  static constexpr double kLogScaleMax = 7.0;
  int Total() const { return components * (1 + 2 * weights); }
  int LogitOffset() const { return 0; }
  int MeanOffset(int q) const { return components + q * weights; }
  int LogScaleOffset(int q) const { return components + components * weights + q * weights; }
};

/// A predicted (or start-conditioned) mixture over w.
struct Mixture {
  Eigen::VectorXd alpha;  ///< [Q], sums to 1 (a dropped component has 0)
  Eigen::MatrixXd mean;   ///< [Q x 2M] (conditioned mean when conditioned)
  Eigen::MatrixXd scale;  ///< [Q x 2M]: Normal sigma, Laplace b (unconditioned marginal scales)
  MixtureFamily family = MixtureFamily::kNormal;
  bool conditioned = false;
  Eigen::Vector2d start = Eigen::Vector2d::Zero();  ///< the condition x(0) (when conditioned)
  Eigen::MatrixXd gain;                             ///< [Q x 2M]: g_x; g_y per component
  int components() const { return static_cast<int>(alpha.size()); }
  /// Per-weight variance of component q (unconditioned): s^2 (Normal) or 2 s^2 (Laplace).
  Eigen::VectorXd Variance(int q) const;
};

enum class ComponentSelection { kAll, kNearest };

struct GenerateOptions {
  int count = 100;           ///< trajectories wanted (>= 1)
  int points = 100;          ///< points per trajectory at uniform tau (>= 2)
  int max_attempts = 2000;   ///< samples drawn at most (>= count)
  double check_step = 0.25;  ///< collision check spacing along each segment (cells, > 0)
  bool reject_collisions = true;
};

struct GenerateStats {
  int accepted = 0;  ///< trajectories returned (< count when max_attempts ran out)
  int rejected = 0;  ///< samples that crossed an occupied cell or left the map
  int attempts = 0;  ///< samples drawn
};

/// True when the polyline [n x 2] leaves the grid or touches an occupied cell at any point checked
/// every <= check_step along each segment (endpoints included).
bool TrajectoryCollides(const BinaryGrid& map, const Eigen::Ref<const Eigen::MatrixX2d>& points,
                        double check_step);

class OtnetModel {
 public:
  /// Per-caller buffers; sized by MakeWorkspace, after which Predict, ConditionOnStart and Generate
  /// do not allocate (for up to the sizes given; the map encoding: see MapEncoder).
  struct Workspace {
    MapEncoder::Workspace encoder;
    Mlp::Workspace mlp;
    Eigen::VectorXd phi;
    Eigen::VectorXf phi_f;
    Mixture mixture, conditioned;
    Eigen::VectorXd taus;
    Eigen::MatrixXd design;  ///< K(taus) [points x M]
    Eigen::VectorXd w, cumulative;
    std::vector<Eigen::MatrixX2d> generated;  ///< [count] x [points x 2]; first `accepted` valid
  };

  OtnetModel() = default;
  /// Error when the MLP's input size differs from the encoder's database size or its output size
  /// from OtnetHead{components, basis.weights()}.Total().
  OtnetModel(MapEncoder encoder, TrajectoryBasis basis, Mlp mlp, MixtureFamily family,
             int components);

  /// Reads an artifact of model type "otnet" (docs/artifact_schema.md); a missing, truncated or
  /// inconsistent file is an Error naming it.
  static OtnetModel Load(const std::string& path);
  /// Writes it (atomically: a temporary file renamed into place).
  void Save(const std::string& path, const std::string& config_yaml, std::int64_t seed) const;

  const MapEncoder& encoder() const { return encoder_; }
  const TrajectoryBasis& basis() const { return basis_; }
  const Mlp& mlp() const { return mlp_; }
  MixtureFamily family() const { return family_; }
  int components() const { return head_.components; }
  const OtnetHead& head() const { return head_; }

  /// Per-weight offset o [2M] of the log-scale clamp: the engine uses
  /// exp(clamp(z - o, kLogScaleMin, kLogScaleMax) + o) for raw network output z. Training clamps
  /// the standardised log-scale and the export folds log s_w into the last layer, so the export
  /// sets o = log s_w and the engine clamps where training did. Default 0. Error on a wrong size
  /// or a non-finite value. Stored in the artifact (/model/log_scale_offset).
  void SetLogScaleOffset(const Eigen::VectorXd& offset);
  const Eigen::VectorXd& log_scale_offset() const { return log_scale_offset_; }

  Workspace MakeWorkspace(int max_count = 100, int points = 100) const;

  /// The mixture for `map` (encode + network) into ws->mixture; returns it.
  const Mixture& Predict(const BinaryGrid& map, Workspace* ws) const;
  /// The mixture for a similarity vector phi [database size] into *out.
  void PredictFromFeatures(const Eigen::Ref<const Eigen::VectorXd>& phi, Workspace* ws,
                           Mixture* out) const;

  /// Exact position marginals of component q at taus [L]: mean [L x 2], covariances of x and of y
  /// [L x L] (K Var K', with the rank-one conditioning when `m` is conditioned).
  void ComponentMarginals(const Mixture& m, int q, const Eigen::VectorXd& taus,
                          Eigen::MatrixX2d* mean, Eigen::MatrixXd* cov_x,
                          Eigen::MatrixXd* cov_y) const;
  /// The per-time density at taus (for ANLL): components with alpha > 0, per-tau diagonal of the
  /// marginals (cov_xy = 0).
  PerTimeDensity Density(const Mixture& m, const Eigen::VectorXd& taus) const;

  /// Conditions `prior` (unconditioned) on x(0) = start into *out. Error when start is not finite
  /// or `prior` is already conditioned. Allocation-free when *out has the sizes of `prior`.
  void ConditionOnStart(const Mixture& prior, const Eigen::Vector2d& start,
                        ComponentSelection selection, Mixture* out) const;

  /// Samples up to options.count trajectories from `mixture` into ws->generated (points at uniform
  /// tau), rejecting those that collide with `map` (when options.reject_collisions). Error when
  /// options exceed the workspace sizes, or when `mixture` is conditioned on a start point outside
  /// the map or inside an occupied cell (naming the point).
  GenerateStats Generate(const BinaryGrid& map, const Mixture& mixture,
                         const GenerateOptions& options, std::mt19937_64* rng, Workspace* ws) const;

 private:
  MapEncoder encoder_;
  TrajectoryBasis basis_;
  Mlp mlp_;
  MixtureFamily family_ = MixtureFamily::kNormal;
  OtnetHead head_;
  Eigen::VectorXd log_scale_offset_;
};

}  // namespace foresight::otnet
