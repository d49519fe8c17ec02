#!/usr/bin/env bash
# Reproduces the SPAN predictor results on the ETH/UCY leave-one-out scenes and the engine
# benchmark; writes results/span_eth_ucy.md. Needs ../shared/data (or FORESIGHT_DATA).
#   experiments/span_eth_ucy.sh [key.path=value ...]      (overrides apply to every scene)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
OUT="$ROOT/results"
mkdir -p "$OUT" "$ROOT/runs"
cd "$ROOT"
for scene in eth hotel univ zara1; do
  # A fresh run per scene (train refuses to mix runs in one directory), unless resuming.
  [[ " $* " == *" --resume "* ]] || rm -rf "runs/span_$scene"
  "$BIN" train "configs/span/eth_ucy_$scene.yaml" --run-dir "runs/span_$scene" train.progress=lines "$@" \
    > "runs/span_$scene.out" 2>&1
done
"$BIN" bench runs/span_eth --json > "$OUT/span_bench_engine.json"
python3 - "$OUT" <<'PY'
import json, sys
out = sys.argv[1]
rows = ["| scene | windows | ADE | FDE | NLL | best-of-20 ADE/FDE | CV ADE | CV FDE | CV NLL | CV best-of-20 |",
        "|---|---|---|---|---|---|---|---|---|---|"]
for s in ["eth", "hotel", "univ", "zara1"]:
    e = json.load(open(f"runs/span_{s}/eval.json"))
    rows.append(f"| {s} | {e['windows']} | {e['ade']:.3f} | {e['fde']:.3f} | {e['nll']:.3f} | "
                f"{e['best_of_20_ade']:.3f}/{e['best_of_20_fde']:.3f} | {e['cv_ade']:.3f} | {e['cv_fde']:.3f} | "
                f"{e['cv_nll']:.3f} | {e['cv_best_of_20_ade']:.3f}/{e['cv_best_of_20_fde']:.3f} |")
b = json.load(open(f"{out}/span_bench_engine.json"))
text = "\n".join(rows) + (f"\n\nEngine batch 1: {b['engine_us']:.2f} us, LibTorch {b['libtorch_us']:.2f} us, "
                          f"ratio {b['ratio']:.1f}x; training {b['train_windows_per_s']:.0f} windows/s\n")
open(f"{out}/span_eth_ucy.md", "w").write(text)
print(text)
PY
