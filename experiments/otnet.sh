#!/usr/bin/env bash
# OTNet (thesis ch 6) on Occ-Traj120: hyper-parameters chosen on the validation maps, the chosen
# run scored on the test maps against k-NN and the mean trajectory, the transfer to sections of the
# Intel-lab map (a Hilbert map from configs/occupancy/intel.yaml), and the engine benchmark. Needs
# ../shared/data (or FORESIGHT_DATA). Writes runs/otnet_*/, results/otnet.md, results/otnet_*.json
# and results/otnet_*.png.
#   experiments/otnet.sh            (from scratch)
#   RESUME=1 experiments/otnet.sh   (skip finished runs, continue killed ones)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
cd "$ROOT"
mkdir -p results runs/otnet_sweep

run() {  # run DIR CONFIG [key=value ...]
  local dir="$1" config="$2"
  shift 2
  if [[ -f "$dir/eval.json" && "${RESUME:-0}" == 1 ]]; then return; fi
  if [[ "${RESUME:-0}" == 1 && -f "$dir/config.yaml" ]]; then
    "$BIN" train "$config" "$@" --run-dir "$dir" --resume
  else
    rm -rf "$dir"
    "$BIN" train "$config" "$@" --run-dir "$dir"
  fi
}

# 1. The validation sweep (eval.plots off), fixed in advance: the thesis's settings (M = 15, Q = 4,
#    l_H = 50, Normal), the Laplace family, narrower and fewer basis functions (less independent
#    per-weight noise in the samples), more components, dropout and other l_H; added after that
#    sweep: its choice trained on the training maps' 8 orientations (data.augment, ~8x the time).
#    The choice reads only the val_* figures (experiments/otnet_select.py: the lowest val_frechet).
while read -r name overrides; do
  [[ -z "$name" || "$name" == \#* ]] && continue
  dir="runs/otnet_sweep/$name"
  # shellcheck disable=SC2086
  run "$dir" configs/otnet/occ_traj120.yaml $overrides eval.plots=false </dev/null
  echo "$overrides" > "$dir/overrides.txt"
done <<'SWEEP'
thesis_m15_q4          otnet.basis=15 otnet.basis_gamma=100 otnet.components=4
laplace_m15_q4         otnet.basis=15 otnet.basis_gamma=100 otnet.components=4 otnet.family=laplace
m15_g300_q16           otnet.basis=15 otnet.basis_gamma=300 otnet.components=16
m15_g300_q16_drop      otnet.basis=15 otnet.basis_gamma=300 otnet.components=16 otnet.dropout=0.2
m12_g200_q16           otnet.basis=12 otnet.basis_gamma=200 otnet.components=16
m10_g150_q16           otnet.basis=10 otnet.basis_gamma=150 otnet.components=16
m10_g150_q16_laplace   otnet.basis=10 otnet.basis_gamma=150 otnet.components=16 otnet.family=laplace
m10_g150_q16_drop      otnet.basis=10 otnet.basis_gamma=150 otnet.components=16 otnet.dropout=0.2
m10_g150_q32           otnet.basis=10 otnet.basis_gamma=150 otnet.components=32
m10_g150_q16_lh200     otnet.basis=10 otnet.basis_gamma=150 otnet.components=16 otnet.length_scale=200
m8_g100_q16            otnet.basis=8 otnet.basis_gamma=100 otnet.components=16
m8_g100_q16_dihedral   otnet.basis=8 otnet.basis_gamma=100 otnet.components=16 data.augment=dihedral
SWEEP
chosen=$(python3 experiments/otnet_select.py runs/otnet_sweep)
echo "chosen on validation: $chosen"

# 2. The Intel-lab occupancy map from the occupancy chapter's pipeline (the Hilbert map: the sharper
#    walls of configs/occupancy/intel.yaml's two models, results/occupancy_intel.md).
if [[ ! -f runs/otnet_intel_map/model.h5 || "${RESUME:-0}" != 1 ]]; then
  rm -rf runs/otnet_intel_map
  "$BIN" train configs/occupancy/intel.yaml model=occupancy.hilbert --run-dir runs/otnet_intel_map
fi

# 3. The chosen settings again with plots and the transfer.
overrides=$(cat "runs/otnet_sweep/$chosen/overrides.txt")
rm -rf runs/otnet_chosen
# shellcheck disable=SC2086
"$BIN" train configs/otnet/occ_traj120.yaml $overrides \
  transfer.occupancy_artifact=runs/otnet_intel_map/model.h5 --run-dir runs/otnet_chosen
cp runs/otnet_chosen/eval.json results/otnet_eval.json
cp runs/otnet_chosen/plots/test_maps.png results/otnet_test_maps.png
cp runs/otnet_chosen/plots/transfer.png results/otnet_transfer.png
python3 experiments/otnet_select.py runs/otnet_sweep --table > results/otnet_sweep.md

# 4. The benchmark: encode a new map and generate 100 start-conditioned trajectories.
"$BIN" bench runs/otnet_chosen --json > results/otnet_bench.json
python3 experiments/otnet_table.py results > results/otnet.md
cat results/otnet.md
