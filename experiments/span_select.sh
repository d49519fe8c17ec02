#!/usr/bin/env bash
# Chooses a SPAN predictor setting by scene-held-out validation and reports it on the ETH/UCY
# leave-one-out test scenes (issue 12), against the committed configs (configs/span/eth_ucy_*.yaml).
#   experiments/span_select.sh NAME SETTING...
# A SETTING is one or more `key.path=value` overrides joined by '+' (so no '+' inside a value), e.g.
# network.residual_to_constant_velocity=true+augment.mirror=true. The configs as they are (the
# working tree; the report names the commit) are always a candidate.
# Validation never reads a test scene. For the test scene S, the training scenes of S's config
# (eth, hotel, zara, univ: files grouped by scene) are held out one at a time: train on the
# training and validation files of the others (the validation files stop early as in the config),
# then evaluate on all files of the held-out scene. The in-scene validation split of the configs
# cannot show what matters here, how a model carries to a scene it has not seen. The score is the
# mean over the inner folds and SEEDS (default 0 1) of ADE / constant-velocity ADE. For each S the
# choice is the first SETTING (list them from simple to elaborate) within MARGIN (default 0.01) of
# the lowest score; it replaces the configs only when it scores at least MARGIN below them.
# Report: the configs and the choice trained on S's config and evaluated on its test file.
# Writes runs/span_select_NAME/ and results/span_select_NAME.md; about 2 minutes per setting and
# seed on 2 cores. REPORT_ONLY=1 rewrites the report from the runs already there; REUSE=1 trains
# only the runs that have no eval.json yet.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
NAME=${1:?usage: span_select.sh NAME SETTING...}
shift
SCENES="${SCENES:-eth hotel univ zara1}"
SEEDS="${SEEDS:-0 1}"
MARGIN="${MARGIN:-0.01}"
OUT=runs/span_select_$NAME
cd "$ROOT"
mkdir -p results "$OUT"

train() {  # train RUN CONFIG [key=value ...]
  local run=$1 config=$2
  shift 2
  [ "${REPORT_ONLY:-0}" != 1 ] || return 0
  [ "${REUSE:-0}" != 1 ] || [ ! -f "$OUT/$run/eval.json" ] || return 0
  rm -rf "$OUT/$run"
  "$BIN" train "$config" --run-dir "$OUT/$run" train.progress=none eval.plot_tracks=0 "$@" \
    > "$OUT/$run.out" 2>&1 || { tail -5 "$OUT/$run.out"; exit 1; }
}
# shellcheck source=experiments/select_lib.sh
source "$ROOT/experiments/select_lib.sh"

# Inner folds, one line each: SCENE GROUP TRAIN_FILES VAL_FILES HELD_OUT_FILES (YAML flow lists).
folds() {
  python3 - "$SCENES" << 'PY'
import sys, yaml
def group(path):  # the scene a file belongs to (../shared/data/eth_ucy/README.md)
    name = path.rsplit("/", 1)[-1]
    for prefix, g in (("biwi_eth", "eth"), ("biwi_hotel", "hotel"), ("crowds_zara", "zara"),
                      ("students", "univ"), ("uni_examples", "univ")):
        if name.startswith(prefix):
            return g
    sys.exit(f"span_select.sh: no scene for data file {path}")
flow = lambda files: "[" + ",".join(files) + "]"
for scene in sys.argv[1].split():
    data = yaml.safe_load(open(f"configs/span/eth_ucy_{scene}.yaml"))["data"]
    train, val = data["train_files"], data["val_files"]
    for g in sorted({group(f) for f in train}):
        keep = lambda files: [f for f in files if group(f) != g]
        held = [f for f in train + val if group(f) == g]
        print(scene, g, flow(keep(train)), flow(keep(val)), flow(held))
PY
}
mapfile -t FOLDS < <(folds)
settings=("" "$@")  # "" = the configs as committed
pids=()
for i in "${!settings[@]}"; do
  mapfile -t o < <(overrides "${settings[$i]}")
  for seed in $SEEDS; do
    for fold in "${FOLDS[@]}"; do
      read -r scene g tr va held <<< "$fold"
      train "val_${scene}_${g}_${i}_s$seed" "configs/span/eth_ucy_$scene.yaml" seed="$seed" \
        "data.train_files=$tr" "data.val_files=$va" "data.test_files=$held" eval.num_samples=1 "${o[@]}" &
      pids+=($!)
      if ((${#pids[@]} == 2)); then wait_all "${pids[@]}"; pids=(); fi
    done
  done
done
wait_all "${pids[@]}"
pids=()

# Per scene: "SCENE WINNER CHOSEN" (setting indices; CHOSEN is 0 unless the winner clears MARGIN).
mapfile -t CHOICES < <(python3 - "$OUT" "$SEEDS" "${#settings[@]}" "$MARGIN" "${FOLDS[@]}" << 'PY'
import json, sys
out, seeds, n, margin, folds = sys.argv[1], sys.argv[2].split(), int(sys.argv[3]), float(sys.argv[4]), sys.argv[5:]
for scene in dict.fromkeys(f.split()[0] for f in folds):
    groups = [f.split()[1] for f in folds if f.split()[0] == scene]
    def ratio(i):
        rs = [json.load(open(f"{out}/val_{scene}_{g}_{i}_s{s}/eval.json")) for g in groups for s in seeds]
        return sum(r["ade"] / r["cv_ade"] for r in rs) / len(rs)
    scores = [ratio(i) for i in range(n)]
    best = min(scores)
    # The first setting (the list runs from simple to elaborate) within MARGIN of the best: a
    # difference below MARGIN is noise between seeds, not a reason for a more elaborate model.
    winner = next(i for i in range(1, n) if scores[i] <= best + margin) if n > 1 else 0
    print(scene, winner, winner if scores[winner] <= scores[0] - margin else 0)
PY
)
for line in "${CHOICES[@]}"; do
  read -r scene winner chosen <<< "$line"
  echo "$scene: chosen '${settings[$chosen]}' (validation winner '${settings[$winner]}')"
  mapfile -t o < <(overrides "${settings[$winner]}")
  train "test_${scene}_0" "configs/span/eth_ucy_$scene.yaml" &
  pids+=($!)
  if [ "$winner" != 0 ]; then  # reported even when it did not clear the margin
    train "test_${scene}_$winner" "configs/span/eth_ucy_$scene.yaml" "${o[@]}" &
    pids+=($!)
  fi
  if ((${#pids[@]} >= 2)); then wait_all "${pids[@]}"; pids=(); fi
done
wait_all "${pids[@]}"
if [ "${REPORT_ONLY:-0}" != 1 ] && { [ "${REUSE:-0}" != 1 ] || [ ! -f "$OUT/commit.txt" ]; }; then  # the configs' commit, when the runs were made
  commit="$(git rev-parse --short HEAD 2> /dev/null || echo unknown)"
  git diff --quiet HEAD -- configs/span 2> /dev/null || commit="$commit with uncommitted changes to configs/span"
  echo "$commit" > "$OUT/commit.txt"
fi
MARGIN="$MARGIN" COMMIT="$(cat "$OUT/commit.txt")" SEEDS="$SEEDS" python3 - "$OUT" "$NAME" "${#settings[@]}" \
  "${settings[@]}" -- "${CHOICES[@]}" -- "${FOLDS[@]}" << 'PY'
import json, os, sys
out, name, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
rest = sys.argv[4:]
settings = rest[:n]
rest = rest[n + 1:]
cut = rest.index("--")
choices = {c.split()[0]: (int(c.split()[1]), int(c.split()[2])) for c in rest[:cut]}
folds = rest[cut + 1:]
seeds = os.environ["SEEDS"].split()
label = lambda i: "configs" if i == 0 else "`" + settings[i].replace("+", " ") + "`"
scenes = list(dict.fromkeys(f.split()[0] for f in folds))

def val_stats(scene, i):
    groups = [f.split()[1] for f in folds if f.split()[0] == scene]
    rs = [json.load(open(f"{out}/val_{scene}_{g}_{i}_s{s}/eval.json")) for g in groups for s in seeds]
    k = len(rs)
    return (sum(r["ade"] / r["cv_ade"] for r in rs) / k, sum(r["nll"] - r["cv_nll"] for r in rs) / k,
            sum(r["calibration"]["within_2sigma"][-1] for r in rs) / k)

val = ["| setting | " + " | ".join(f"{s}: ADE / CV ADE, NLL - CV NLL, 2-sigma at 4.8 s" for s in scenes) + " |",
       "|---" * (len(scenes) + 1) + "|"]
for i in range(n):
    cells = []
    for s in scenes:
        r, d, c = val_stats(s, i)
        mark = " **chosen**" if choices[s][1] == i else (" (winner, short of the margin)" if choices[s][0] == i else "")
        cells.append(f"{r:.3f}, {d:+.3f}, {100 * c:.0f} %{mark}")
    val.append(f"| {label(i)} | " + " | ".join(cells) + " |")

def row(scene, run, method):
    e = json.load(open(f"{out}/test_{scene}_{run}/eval.json"))
    cal = e["calibration"]
    return (f"| {scene} | {method} | {e['windows']} | {e['ade']:.3f} ({e['ade'] / e['cv_ade']:.2f}x CV) | "
            f"{e['fde']:.3f} | {e['nll']:.3f} | {e['cv_ade']:.3f} / {e['cv_fde']:.3f} / {e['cv_nll']:.3f} | "
            f"{100 * cal['within_1sigma'][-1]:.0f} / {100 * cal['within_2sigma'][-1]:.0f} % |"), e["ade"] / e["cv_ade"]
test = ["| scene | model | windows | ADE | FDE | NLL | constant velocity ADE / FDE / NLL | 1- / 2-sigma coverage at 4.8 s (nominal 39 / 86 %) |",
        "|---|---|---|---|---|---|---|---|"]
ratios = {"configs": [], "reported": []}
for s in scenes:
    winner, chosen = choices[s]
    line, r = row(s, "0", "configs")
    test.append(line)
    ratios["configs"].append(r)
    if winner != 0:
        note = "" if winner == chosen else " (short of the margin: not adopted)"
        line, r = row(s, str(winner), f"{label(winner)}{note}")
        test.append(line)
        ratios["reported"].append(r if winner == chosen else ratios["configs"][-1])
    else:
        ratios["reported"].append(r)
mean = lambda v: sum(v) / len(v)
text = (f"# SPAN predictor settings chosen by scene-held-out validation: {name} (generated by experiments/span_select.sh)\n\n"
        f"configs: configs/span/eth_ucy_<scene>.yaml at {os.environ['COMMIT']}.\n\n"
        "Validation (never reads a test scene): for each test scene, each of the scenes its config trains on is held out in turn; "
        "the model trains on the others' training and validation files and is evaluated on all of the held-out scene's files. "
        f"Means over those folds and seeds {' and '.join(seeds)}. The choice is the first setting (in the order listed) within "
        f"{os.environ['MARGIN']} of the lowest mean ADE / constant-velocity ADE; it replaces the configs only when at least "
        f"{os.environ['MARGIN']} below them.\n\n" + "\n".join(val) +
        "\n\nReported: trained on the scene's config (seed 0), evaluated on its test file.\n\n" + "\n".join(test) +
        f"\n\nMean ADE / CV ADE over the scenes: configs {mean(ratios['configs']):.3f}, with the adopted choices "
        f"{mean(ratios['reported']):.3f}.\n")
open(f"results/span_select_{name}.md", "w").write(text)
print(text)
PY
