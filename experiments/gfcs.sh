#!/usr/bin/env bash
# Self-supervised GFCS (thesis ch 9): the loop over problems 1-50 of six MotionBenchMaker families,
# then the learned sampler against the uniform one (same budget, same seeds) and the fabric on the
# held-out problems 51-75 (the data holds 75 per family). Needs ../shared/data (or FORESIGHT_DATA). Writes runs/gfcs_all/ and
# results/gfcs.md, results/gfcs_eval.json.
#   experiments/gfcs.sh [key.path=value ...]          (overrides of configs/gfcs/all_families.yaml)
#   RESUME=1 experiments/gfcs.sh                      (continue a killed run)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
RUN="$ROOT/runs/gfcs_all"
cd "$ROOT"
mkdir -p results runs
if [[ "${RESUME:-0}" == 1 ]]; then
  "$BIN" train configs/gfcs/all_families.yaml --run-dir "$RUN" --resume "$@"
else
  rm -rf "$RUN"
  "$BIN" train configs/gfcs/all_families.yaml --run-dir "$RUN" "$@"
fi
cp "$RUN/eval.json" results/gfcs_eval.json
python3 experiments/gfcs_table.py results/gfcs_eval.json "$RUN" > results/gfcs.md
cat results/gfcs.md
