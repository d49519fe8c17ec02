#pragma once
/// The one query interface of every occupancy map (Hilbert map, Fast-BHM, full BHM, grid), as used
/// by navigation, constrained prediction and imitation. A map is immutable once loaded; each
/// caller owns a MapWorkspace, so one map serves many threads. Queries never allocate.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace foresight::occupancy {

/// Model types of occupancy-map artifacts (the artifact's root attribute `model_type`).
inline constexpr const char* kHilbertMapType = "occupancy.hilbert";
inline constexpr const char* kFastBhmType = "occupancy.fast_bhm";
inline constexpr const char* kBhmType = "occupancy.bhm";
inline constexpr const char* kGridMapType = "occupancy.grid";

/// One point's answer.
struct QueryResult {
  double probability = 0.5;     ///< p(occupied | x)
  double dp_dx = 0, dp_dy = 0;  ///< gradient of the probability w.r.t. the query position (1/m)
  /// Posterior variance of the latent logit f(x) = w' phi(x) (Bayesian maps); 0 for maps without
  /// weight uncertainty. Where the map knows nothing (outside its extent) this is the prior
  /// variance and the probability is the prior 0.5.
  double variance = 0;
};

/// Per-caller scratch buffers, sized by OccupancyMap::MakeWorkspace().
struct MapWorkspace {
  std::vector<int> index;
  std::vector<double> phi, dphi_dx, dphi_dy, scratch;
};

/// Results of a batch query, one entry per point (resize once, reuse).
struct MapQueryBatch {
  Eigen::VectorXd probability, variance;
  Eigen::Matrix2Xd gradient;  ///< column i: (dp/dx, dp/dy) of point i
  void Resize(Eigen::Index n) {
    probability.resize(n);
    variance.resize(n);
    gradient.resize(2, n);
  }
};

class Map {
 public:
  virtual ~Map() = default;
  virtual std::string model_type() const = 0;
  virtual MapWorkspace MakeWorkspace() const = 0;
  /// Probability, gradient and variance at (x, y) in the map frame (m).
  virtual QueryResult Query(double x, double y, MapWorkspace* ws) const = 0;
  /// Probability only (cheaper where a map can skip the gradient).
  virtual double Probability(double x, double y, MapWorkspace* ws) const {
    return Query(x, y, ws).probability;
  }
  /// Batch query of points [2 x n] into `out` (resized if needed; no allocation when sized).
  virtual void QueryBatch(const Eigen::Ref<const Eigen::Matrix2Xd>& points, MapWorkspace* ws,
                          MapQueryBatch* out) const;
  /// Probabilities only, into `out` [n].
  virtual void ProbabilityBatch(const Eigen::Ref<const Eigen::Matrix2Xd>& points, MapWorkspace* ws,
                                Eigen::Ref<Eigen::VectorXd> out) const;
  /// Axis-aligned extent [x_min, x_max, y_min, y_max] where the map holds information (m).
  virtual Eigen::Vector4d Extent() const = 0;
};

/// Loads any occupancy-map artifact (model types above). A missing, truncated or non-map artifact
/// is an Error naming the file and what was found.
std::unique_ptr<Map> LoadMap(const std::string& path);

}  // namespace foresight::occupancy
