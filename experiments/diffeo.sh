#!/usr/bin/env bash
# Diffeomorphic templates (thesis ch 8): every LASA shape (ours vs Euclideanizing Flows, an
# obstacle on each shape's demonstrations) and the JACO push-box / lift-box tasks in C-space, then
# the step-time benchmark. Needs ../shared/data (or FORESIGHT_DATA). Writes runs/diffeo_*/,
# results/diffeo.md and results/diffeo_{lasa,jaco_push_box,jaco_lift_box,bench}.json.
#   experiments/diffeo.sh            (all three runs from scratch)
#   RESUME=1 experiments/diffeo.sh   (continue killed runs)
#   RUNS="jaco_push_box jaco_lift_box" experiments/diffeo.sh   (only those runs; the bench keeps the
#     previous figures of a part whose run is absent)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
cd "$ROOT"
mkdir -p results runs
for name in ${RUNS:-lasa jaco_push_box jaco_lift_box}; do
  run="runs/diffeo_$name"
  if [[ "${RESUME:-0}" == 1 && -f "$run/config.yaml" ]]; then
    "$BIN" train "configs/diffeo/$name.yaml" --run-dir "$run" --resume
  else
    rm -rf "$run"
    "$BIN" train "configs/diffeo/$name.yaml" --run-dir "$run"
  fi
  cp "$run/eval.json" "results/diffeo_$name.json"
done
bench_part() {  # PART ARTIFACT: a fresh bench, or the previous figures when the artifact is absent
  if [ -f "$2" ]; then
    "$BIN" bench "$2" --json
  else
    python3 -c 'import json, sys; print(json.dumps(json.load(open(sys.argv[1]))[sys.argv[2]]))' \
      results/diffeo_bench.json "$1"
  fi
}
planar=$(bench_part planar runs/diffeo_lasa/models/Sshape.h5)
cspace=$(bench_part cspace runs/diffeo_jaco_push_box/models/push_box.h5)
printf '{"planar":\n%s\n, "cspace":\n%s\n}\n' "$planar" "$cspace" > results/diffeo_bench.json
python3 experiments/diffeo_table.py results > results/diffeo.md
cat results/diffeo.md
