#pragma once
/// The exported imitation model of diffeomorphic templates (thesis ch 8): an ImitationSystem with
/// the normalisation of its coordinates, as one artifact (docs/artifact_schema.md) of model_type
/// "diffeo_template":
///   /model attrs  dimension (2 | 3), steps (K), time (T), speed, gamma, cutoff_radius, spacing,
///                 segments (S, optional: absent = 1)
///   /model/lower [D], /model/counts [D] (int64)   the RBF grid of inducing states
///   /model/weights [S m x D]                       W_g of V_g(s) = W_g' phi(s), m = prod counts
///   /model/goal [D]                                the goal in normalised coordinates
///   /normalisation/offset [D], attr scale          x_normalised = (x_raw - offset) * scale
/// Loading checks every shape, finite value and range (an Error naming the file and the field)
/// and refuses a flow that CheckInvertible finds non-invertible on a lattice over the grid's box.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "inference/imitation/rbf_flow.h"

namespace foresight::imitation {

inline constexpr const char* kTemplateModelType = "diffeo_template";

struct TemplateNormalisation {
  Eigen::VectorXd offset;  ///< [D] subtracted from raw coordinates
  double scale = 1;        ///< > 0, multiplies after the offset
};

template <int D>
struct TemplateArtifact {
  ImitationSystem<D> system;
  TemplateNormalisation normalisation;
  std::string config_yaml;
  std::int64_t seed = 0;
};

/// Writes the artifact atomically (path.tmp, checked close, rename). An Error when the
/// normalisation is not [D] finite offsets with a positive finite scale.
template <int D>
void SaveTemplate(const std::string& path, const ImitationSystem<D>& system,
                  const TemplateNormalisation& normalisation, const std::string& config_yaml,
                  std::int64_t seed);

/// The dimension (2 or 3) of a diffeo_template artifact; an Error otherwise.
int TemplateDimension(const std::string& path);

/// Loads and checks a diffeo_template artifact of dimension D (see the file comment).
template <int D>
TemplateArtifact<D> LoadTemplate(const std::string& path);

/// The points LoadTemplate checks invertibility on: a lattice over the inducing-state box with
/// about twice the grid's resolution (at most 45 per axis in 2-D, 13 in 3-D), shifted off the
/// grid's symmetric positions.
template <int D>
Eigen::Matrix<double, D, Eigen::Dynamic> InvertibilityCheckPoints(const RbfGrid<D>& grid);

}  // namespace foresight::imitation
