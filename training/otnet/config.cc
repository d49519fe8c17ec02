#include "training/otnet/config.h"

#include "core/error.h"
#include "core/layer_widths.h"

namespace foresight::otnet {

void ExperimentConfig::Validate(const std::string& source) const {
  FS_THROW_UNLESS(model == "otnet", source, ": model: '", model, "', expected 'otnet'");
  FS_THROW_UNLESS(data.val_fraction > 0 && data.test_fraction > 0, source,
                  ": data.val_fraction and data.test_fraction must be > 0 (maps are chosen on "
                  "validation and scored on the test split)");
  FS_THROW_UNLESS(data.val_fraction + data.test_fraction < 0.9, source,
                  ": data.val_fraction + data.test_fraction = ",
                  data.val_fraction + data.test_fraction, " leaves too few training maps");
  FS_THROW_UNLESS(otnet.ridge > 0, source, ": otnet.ridge: ", otnet.ridge,
                  " must be > 0 (the fit of M basis weights needs it when points are few)");
  CheckLayerWidths(otnet.hidden, source, "otnet.hidden");
  FS_THROW_UNLESS(eval.max_attempts >= eval.generated, source, ": eval.max_attempts (",
                  eval.max_attempts, ") is below eval.generated (", eval.generated, ")");
  if (!transfer.occupancy_artifact.empty()) {
    FS_THROW_UNLESS(!transfer.sections.empty() && transfer.sections.size() % 3 == 0, source,
                    ": transfer.sections: ", transfer.sections.size(),
                    " numbers; expected x_min, y_min, side (m) per section");
    for (std::size_t i = 2; i < transfer.sections.size(); i += 3)
      FS_THROW_UNLESS(transfer.sections[i] > 0, source, ": transfer.sections[", i, "]: side ",
                      transfer.sections[i], " must be positive");
    FS_THROW_UNLESS(transfer.starts.size() % 2 == 0, source,
                    ": transfer.starts: ", transfer.starts.size(),
                    " numbers; expected x, y pairs (section cells)");
  }
}

}  // namespace foresight::otnet
