#!/usr/bin/env bash
# Directional maps on path-grouped 10-fold cross-validation (thesis ch 4, issue 11): the crossing
# flow (synthetic), P1 and P2 (../shared/data/directional_grid_maps_sim); every method of the
# pipeline including the 1-NN / k-NN baselines; AL at several caps and the weighted MRE.
# Writes runs/directional_<data>_path/, results/directional_<data>_path.json and
# results/directional_path_folds.md. About 10 minutes on 2 cores.
#   experiments/directional_path.sh [key.path=value ...]      (overrides apply to every run)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
cd "$ROOT"
mkdir -p runs results
for d in crossing p1 p2; do
  rm -rf "runs/directional_${d}_path"
  "$BIN" train "configs/directional/$d.yaml" eval.folds_by=path --run-dir "runs/directional_${d}_path" "$@" \
    > "runs/directional_${d}_path.out" 2>&1
  cp "runs/directional_${d}_path/eval.json" "results/directional_${d}_path.json"
done
python3 experiments/directional_table.py results > results/directional_path_folds.md
cat results/directional_path_folds.md
