// Manipulation (thesis ch 9) as an experiment kind: GFCS, the geometric fabric and the OMPL
// planners over MotionBenchMaker or synthetic problems. It trains nothing (the learned sampler is
// the `gfcs` kind's job) and is run by `foresight plan`.

#include "training/kinds.h"
#include "training/manipulation/config.h"

namespace foresight::manipulation {

ExperimentKind Kind() {
  ExperimentKind k;
  k.tag = "manipulation";
  k.summary = "Manipulation: GFCS, geometric fabrics and OMPL planners (thesis ch 9)";
  k.configs = "configs/manipulation/*.yaml; run by `foresight plan`";
  k.reference = [] { return config::ReferenceTable<ExperimentConfig>(); };
  k.no_step_hint = "run it with `foresight plan CONFIG --run-dir DIR`";
  SetBenchStep(&k);
  return k;
}

}  // namespace foresight::manipulation
