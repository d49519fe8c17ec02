#include "inference/mapping/occupancy_map.h"

#include "core/error.h"
#include "inference/engine/artifact.h"
#include "inference/mapping/grid_map.h"
#include "inference/mapping/hinge_map.h"

namespace foresight::occupancy {

void Map::QueryBatch(const Eigen::Ref<const Eigen::Matrix2Xd>& points, MapWorkspace* ws,
                     MapQueryBatch* out) const {
  if (out->probability.size() != points.cols()) out->Resize(points.cols());
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const QueryResult q = Query(points(0, i), points(1, i), ws);
    out->probability[i] = q.probability;
    out->variance[i] = q.variance;
    out->gradient(0, i) = q.dp_dx;
    out->gradient(1, i) = q.dp_dy;
  }
}

void Map::ProbabilityBatch(const Eigen::Ref<const Eigen::Matrix2Xd>& points, MapWorkspace* ws,
                           Eigen::Ref<Eigen::VectorXd> out) const {
  FS_THROW_UNLESS(out.size() == points.cols(), "ProbabilityBatch: output has ", out.size(),
                  " entries for ", points.cols(), " points");
  for (Eigen::Index i = 0; i < points.cols(); ++i)
    out[i] = Probability(points(0, i), points(1, i), ws);
}

std::unique_ptr<Map> LoadMap(const std::string& path) {
  std::string type;
  {
    const Artifact a = Artifact::Open(path, "");
    type = a.model_type();
  }
  if (type == kHilbertMapType || type == kFastBhmType || type == kBhmType) {
    return std::make_unique<HingeMap>(HingeMap::Load(path, type));
  }
  if (type == kGridMapType) return std::make_unique<GridMap>(GridMap::Load(path));
  Fail(path, ": artifact holds a '", type, "' model, not an occupancy map");
}

}  // namespace foresight::occupancy
