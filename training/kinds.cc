#include "training/kinds.h"

#ifdef FORESIGHT_WITH_TORCH
#include "embedded_config.h"
#endif

namespace foresight {

ExperimentRegistry BuiltinKinds() {
  ExperimentRegistry r;
#ifdef FORESIGHT_WITH_TORCH
  r.Add(span::Kind(kEmbeddedDefaultConfig));
#endif
  r.Add(occupancy::Kind());
#ifdef FORESIGHT_WITH_TORCH
  r.Add(directional::Kind());
#endif
  r.Add(nav::Kind());
  r.Add(manipulation::Kind());
#ifdef FORESIGHT_WITH_TORCH
  r.Add(gfcs::Kind());
  r.Add(imitation::Kind());
  r.Add(otnet::Kind());
  r.Add(constrained::Kind());
  r.SetDefault("span_predictor");
#endif
  return r;
}

}  // namespace foresight
