#!/usr/bin/env bash
# How far a re-run of the self-supervised GFCS loop moves the held-out comparison (issue 17): the
# whole of experiments/gfcs.sh (loop on problems 1-50, held-out eval on 51-75) with other seeds.
# The seed drives the loop's problem order, SGLD negatives and training batches, the network's
# initialisation and the eval's candidate draws (uniform and learned alike). Seed 0 is the shipped
# run (results/gfcs_eval.json, from experiments/gfcs.sh). About 16 min per seed on 2 cores.
#   experiments/gfcs_seeds.sh                 (seeds 1 and 2)
#   SEEDS="1 2 3" experiments/gfcs_seeds.sh   (others; RESUME=1 continues killed runs)
# A seed whose run finished (runs/gfcs_seed_<s>/eval.json) is kept; delete the folder to redo it.
# Writes runs/gfcs_seed_<s>/ and results/gfcs_seeds.md.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
cd "$ROOT"
mkdir -p results runs
args=("results/gfcs_eval.json=0")
for s in ${SEEDS:-1 2}; do
  [[ "$s" =~ ^[1-9][0-9]*$ ]] || { echo "SEEDS: '$s' is not a positive integer (seed 0 is experiments/gfcs.sh's run)" >&2; exit 1; }
  run="runs/gfcs_seed_$s"
  if [[ -f "$run/eval.json" ]]; then
    echo "seed $s: $run finished before, kept"
  elif [[ "${RESUME:-0}" == 1 && -f "$run/config.yaml" ]]; then
    "$BIN" train configs/gfcs/all_families.yaml --run-dir "$run" --resume "seed=$s"
  else
    rm -rf "$run"
    "$BIN" train configs/gfcs/all_families.yaml --run-dir "$run" "seed=$s"
  fi
  args+=("$run/eval.json=$s")
done
python3 experiments/gfcs_seeds_table.py "${args[@]}" > results/gfcs_seeds.md
cat results/gfcs_seeds.md
