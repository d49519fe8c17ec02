#!/usr/bin/env bash
# The coupled (learning) Fast-BHM on the Intel Research Lab log (thesis ch 3): the map at 0.5 m
# with its fit time, the fit time at 0.4 m, and the fusion of four quadrant robots; plus the fusion
# on the simulated two-robot floor plan (no ../shared needed for that one). Needs ../shared/data (or
# FORESIGHT_DATA) for Intel. Writes runs/intel_coupled*/, runs/*_fusion_coupled/ and
# results/occupancy_intel_coupled.json (eval.json with the fit's training summary, fit times the
# median of REPEATS runs), results/occupancy_intel_fusion_coupled.json,
# results/occupancy_synthetic_fusion_coupled.json.
#   experiments/occupancy.sh                (REPEATS=3 by default)
# About 1 minute on 2 cores.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
REPEATS="${REPEATS:-3}"
[[ "$REPEATS" =~ ^[1-9][0-9]*$ ]] || { echo "REPEATS=$REPEATS: a positive number of runs" >&2; exit 1; }
cd "$ROOT"
mkdir -p results runs

train() {  # train DIR CONFIG [key=value ...]
  local dir="$1" config="$2"
  shift 2
  rm -rf "$dir"
  "$BIN" train "$config" "$@" --run-dir "$dir" > "$dir.out" 2>&1 || { tail -5 "$dir.out"; exit 1; }
}

# The fit time is a wall time: repeat and keep the run with the median time.
for i in $(seq 1 "$REPEATS"); do
  train "runs/intel_coupled_$i" configs/occupancy/intel.yaml
  train "runs/intel_coupled_04_$i" configs/occupancy/intel.yaml features.spacing=0.4
done
train runs/intel_fusion_coupled configs/occupancy/intel_fusion.yaml
train runs/synthetic_fusion_coupled configs/occupancy/synthetic_fusion.yaml
cp runs/intel_fusion_coupled/eval.json results/occupancy_intel_fusion_coupled.json
cp runs/synthetic_fusion_coupled/eval.json results/occupancy_synthetic_fusion_coupled.json

python3 - "$REPEATS" <<'PY'
import json, statistics, sys
repeats = int(sys.argv[1])
def runs(prefix):
    out = []
    for i in range(1, repeats + 1):
        d = f"runs/{prefix}_{i}"
        out.append((json.load(open(f"{d}/training_summary.json")), json.load(open(f"{d}/eval.json"))))
    return out
res = runs("intel_coupled")
times = [t["seconds"] for t, _ in res]
median = statistics.median_low(times)
training, evaluation = next(r for r in res if r[0]["seconds"] == median)
evaluation["training"] = training
evaluation["training"]["seconds_of_repeats"] = times
evaluation["fit_seconds_at_0.4m_of_repeats"] = [t["seconds"] for t, _ in runs("intel_coupled_04")]
evaluation["fit_seconds_at_0.4m"] = statistics.median_low(evaluation["fit_seconds_at_0.4m_of_repeats"])
json.dump(evaluation, open("results/occupancy_intel_coupled.json", "w"), indent=1)
print(f"coupled fit at 0.5 m: median {median:.3f} s of {times}; AUC {evaluation['auc']}")
print(f"coupled fit at 0.4 m: median {evaluation['fit_seconds_at_0.4m']:.3f} s")
PY
