#include "training/constrained/config.h"

#include "core/error.h"
#include "core/layer_widths.h"

namespace foresight::constrained {

void ExperimentConfig::Validate(const std::string& source) const {
  FS_THROW_UNLESS(model == "constrained", source, ": model: '", model, "', expected 'constrained'");
  data.Validate(source);
  FS_THROW_UNLESS(network.u_param == UParam::kDiagonal, source,
                  ": network.u_param: cholesky; the constraint projection optimises the "
                  "log-diagonal of U (thesis ch 7), so set network.u_param: diagonal");
  FS_THROW_UNLESS(split.val_fraction > 0, source,
                  ": split.val_fraction must be > 0 (the validation loss chooses the checkpoint)");
  FS_THROW_UNLESS(split.val_fraction + split.test_fraction < 0.9, source,
                  ": split.val_fraction + split.test_fraction = ",
                  split.val_fraction + split.test_fraction, " leaves too few training tracks");
  FS_THROW_UNLESS(constraint.margin > 0, source,
                  ": constraint.margin must be > 0 (the solver's tolerance is half of it; with 0 "
                  "a solved point may sit just above epsilon)");
  FS_THROW_UNLESS(constraint.margin < constraint.epsilon, source, ": constraint.margin (",
                  constraint.margin, ") must be below constraint.epsilon (", constraint.epsilon,
                  ")");
  FS_THROW_UNLESS(
      !constraint.choose_check || constraint.choose_quadrature, source,
      ": constraint.choose_check needs constraint.choose_quadrature (the check is chosen "
      "on windows projected with the chosen rule)");
  CheckLayerWidths(network.hidden, source, "network.hidden");
  CheckLayerWidths(naive.hidden, source, "naive.hidden");
}

}  // namespace foresight::constrained
