#include "inference/mapping/fusion.h"

#include <cmath>
#include <limits>

#include "core/error.h"

namespace foresight::occupancy {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

void RequireFastBhm(const HingeMap& map, const std::string& name) {
  FS_THROW_UNLESS(map.kind() == HingeMapKind::kFastBhm, name, ": fusion needs ", kFastBhmType,
                  " maps, this one is ", map.model_type());
}

void RequireSameGrid(const HingeMap& a, const std::string& name_a, const HingeMap& b,
                     const std::string& name_b) {
  FS_THROW_UNLESS(a.grid().SameFeatures(b.grid()), name_b, ": feature grid (", b.grid().Describe(),
                  ") differs from that of ", name_a, " (", a.grid().Describe(), ")");
  FS_THROW_UNLESS(a.prior_mean() == b.prior_mean() && a.prior_variance() == b.prior_variance(),
                  name_b, ": weight prior N(", b.prior_mean(), ", ", b.prior_variance(),
                  ") differs from that of ", name_a, " N(", a.prior_mean(), ", ",
                  a.prior_variance(), ")");
}

}  // namespace

WeightEstimate EstimateOf(const HingeMap& map) {
  RequireFastBhm(map, "map");
  return {map.weights().mean, map.weights().variance};
}

WeightEstimate IncrementOf(const HingeMap& local, const HingeMap& last_global) {
  RequireFastBhm(local, "local map");
  RequireFastBhm(last_global, "last global map");
  RequireSameGrid(last_global, "last global map", local, "local map");
  const auto& mu_mn = local.weights().mean;
  const auto& s2_mn = local.weights().variance;
  const auto& mu_m = last_global.weights().mean;
  const auto& s2_m = last_global.weights().variance;
  WeightEstimate inc{Eigen::VectorXd::Zero(mu_m.size()),
                     Eigen::VectorXd::Constant(mu_m.size(), kInf)};
  for (Eigen::Index t = 0; t < mu_m.size(); ++t) {
    const double precision = 1.0 / s2_mn[t] - 1.0 / s2_m[t];
    if (!(s2_mn[t] < s2_m[t]) || !(precision > 0)) continue;  // learned nothing for this weight
    inc.variance[t] = 1.0 / precision;
    inc.mean[t] = inc.variance[t] * (mu_mn[t] / s2_mn[t] - mu_m[t] / s2_m[t]);
  }
  return inc;
}

HingeMap Conflate(const HingeGrid& grid, const std::vector<WeightEstimate>& estimates,
                  const FusionOptions& options, double prior_mean, double prior_variance,
                  const HingeMap* base) {
  const Eigen::Index t_size = grid.size();
  Eigen::VectorXd precision = Eigen::VectorXd::Zero(t_size), info = Eigen::VectorXd::Zero(t_size);
  if (base != nullptr) {
    RequireFastBhm(*base, "base map");  // a Hilbert map has no variances to conflate
    FS_THROW_UNLESS(base->grid().SameFeatures(grid), "conflation: base map grid differs");
    precision = base->weights().variance.cwiseInverse();
    info = base->weights().mean.cwiseProduct(precision);
  }
  for (const WeightEstimate& e : estimates) {
    FS_THROW_UNLESS(e.mean.size() == t_size && e.variance.size() == t_size,
                    "conflation: estimate of ", e.mean.size(), " weights for a grid of ", t_size);
    for (Eigen::Index t = 0; t < t_size; ++t) {
      const double s2 = e.variance[t];
      if (!(s2 < options.variance_threshold) || !(s2 > 0)) continue;
      precision[t] += 1.0 / s2;
      info[t] += e.mean[t] / s2;
    }
  }
  HingeWeights w;
  w.mean.resize(t_size);
  w.variance.resize(t_size);
  for (Eigen::Index t = 0; t < t_size; ++t) {
    if (precision[t] > 0) {
      w.variance[t] = 1.0 / precision[t];
      w.mean[t] = info[t] * w.variance[t];
    } else {
      w.variance[t] = prior_variance;
      w.mean[t] = prior_mean;
    }
  }
  return HingeMap(HingeMapKind::kFastBhm, grid, std::move(w), prior_mean, prior_variance);
}

HingeMap FuseMaps(const std::vector<const HingeMap*>& maps, const std::vector<std::string>& names,
                  const FusionOptions& options, const HingeMap* last_global) {
  FS_THROW_UNLESS(!maps.empty(), "fusion: no maps given");
  FS_THROW_UNLESS(names.size() == maps.size(), "fusion: ", names.size(), " names for ", maps.size(),
                  " maps");
  for (std::size_t i = 0; i < maps.size(); ++i) {
    RequireFastBhm(*maps[i], names[i]);
    RequireSameGrid(*maps[0], names[0], *maps[i], names[i]);
  }
  const HingeMap& first = *maps[0];
  std::vector<WeightEstimate> estimates;
  if (last_global != nullptr) {
    RequireFastBhm(*last_global, "last global map");
    RequireSameGrid(first, names[0], *last_global, "last global map");
    for (const HingeMap* m : maps) estimates.push_back(IncrementOf(*m, *last_global));
  } else {
    for (const HingeMap* m : maps) estimates.push_back(EstimateOf(*m));
  }
  return Conflate(first.grid(), estimates, options, first.prior_mean(), first.prior_variance(),
                  last_global);
}

}  // namespace foresight::occupancy
