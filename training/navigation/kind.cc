// Closed-loop navigation as an experiment kind (thesis ch 5). It trains nothing itself (its
// predictor is a span_predictor run) and is run by `foresight navigate`.

#include "training/kinds.h"
#include "training/navigation/config.h"

namespace foresight::nav {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "navigation";
  k.summary = "Navigation through crowds: SPAN and baselines (thesis ch 5)";
  k.configs = "configs/navigation/sim1.yaml, sim2.yaml, dataset.yaml; run by `foresight navigate`";
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.no_step_hint = "run it with `foresight navigate CONFIG --run-dir DIR`";
  return k;
}

}  // namespace foresight::nav
