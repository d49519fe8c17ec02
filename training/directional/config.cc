#include "training/directional/config.h"

namespace foresight::directional {
void ExperimentConfig::Validate(const std::string& source) const {
  const ExperimentConfig& c = *this;
  FS_THROW_UNLESS(c.model == "directional", source, ": key 'model': value '", c.model,
                  "' is not 'directional'");
  FS_THROW_UNLESS(
      c.data.format == Source::kCrossing || !c.data.file.empty(), source,
      ": key 'data.file' must name a data file when data.format is grid_csv or edinburgh");
  const auto& f = c.features;
  FS_THROW_UNLESS(f.auto_extent || (f.x_max > f.x_min && f.y_max > f.y_min), source,
                  ": keys 'features.x_min/x_max/y_min/y_max' give an empty extent");
  FS_THROW_UNLESS(f.auto_time_range || f.t_max >= f.t_min, source,
                  ": key 'features.t_max' must be >= features.t_min");
  FS_THROW_UNLESS(static_cast<double>(f.cells_x) * f.cells_y <= 200000, source,
                  ": keys 'features.cells_x' x ",
                  "'features.cells_y' = ", static_cast<double>(f.cells_x) * f.cells_y,
                  " inducing points; at most 200000");
  FS_THROW_UNLESS(
      c.eval.spatiotemporal || c.eval.spatial, source,
      ": keys 'eval.spatiotemporal' and 'eval.spatial' are both false: no network to train");
  FS_THROW_UNLESS(c.eval.max_folds <= c.eval.folds, source, ": key 'eval.max_folds' (",
                  c.eval.max_folds, ") must be <= eval.folds (", c.eval.folds, ")");
}

}  // namespace foresight::directional
