#include "training/span/config.h"

#include <cmath>

#include "core/layer_widths.h"

namespace foresight::span {

void ExperimentConfig::Validate(const std::string& source) const {
  const ExperimentConfig& c = *this;
  FS_THROW_UNLESS(c.model == "span_predictor", source, ": key 'model': value '", c.model,
                  "' is not 'span_predictor'");
  FS_THROW_UNLESS(c.data.synthetic.speed_max >= c.data.synthetic.speed_min, source,
                  ": key 'data.synthetic.speed_max' must be >= data.synthetic.speed_min");
  FS_THROW_UNLESS(c.data.synthetic.max_steps >= c.data.synthetic.min_steps, source,
                  ": key 'data.synthetic.max_steps' must be >= data.synthetic.min_steps");
  FS_THROW_UNLESS(c.data.val_fraction + c.data.test_fraction < 1.0, source,
                  ": keys 'data.val_fraction' + 'data.test_fraction' must be < 1");
  FS_THROW_UNLESS(
      c.data.synthetic.min_steps >= c.windows.observed + c.windows.predicted ||
          c.data.format != TrackFormat::kSynthetic,
      source, ": key 'data.synthetic.min_steps' must be >= windows.observed + windows.predicted");
  CheckLayerWidths(c.network.hidden, source, "network.hidden");
  for (const double scale : c.augment.speed_scales)
    FS_THROW_UNLESS(std::abs(scale - 1.0) > 1e-9, source, ": key 'augment.speed_scales': value ",
                    scale, " (the data enter at scale 1 anyway; list only the extra scales)");
}

}  // namespace foresight::span
