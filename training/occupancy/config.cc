#include "training/occupancy/config.h"

#include <algorithm>

namespace foresight::occupancy {
void ExperimentConfig::Validate(const std::string& source) const {
  const ExperimentConfig& c = *this;
  static const std::vector<std::string> kModels{"occupancy.fast_bhm", "occupancy.bhm",
                                                "occupancy.hilbert", "occupancy.grid",
                                                "occupancy.fusion"};
  FS_THROW_UNLESS(std::find(kModels.begin(), kModels.end(), c.model) != kModels.end(), source,
                  ": key 'model': value '", c.model,
                  "' is not one of occupancy.fast_bhm, occupancy.bhm, ",
                  "occupancy.hilbert, occupancy.grid, occupancy.fusion");
  FS_THROW_UNLESS(c.data.test_offset < c.data.test_every, source, ": key 'data.test_offset' (",
                  c.data.test_offset, ") must be smaller than data.test_every (", c.data.test_every,
                  ")");
  FS_THROW_UNLESS(c.data.format != ScanSource::kCarmen || !c.data.file.empty(), source,
                  ": key 'data.file' must name a CARMEN log when data.format is carmen");
  FS_THROW_UNLESS(c.features.x_max > c.features.x_min && c.features.y_max > c.features.y_min,
                  source, ": keys 'features.x_min/x_max/y_min/y_max' give an empty extent");
  FS_THROW_UNLESS(c.grid.x_max > c.grid.x_min && c.grid.y_max > c.grid.y_min, source,
                  ": keys 'grid.x_min/x_max/y_min/y_max' give an empty extent");
}

}  // namespace foresight::occupancy
