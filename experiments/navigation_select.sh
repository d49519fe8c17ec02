#!/usr/bin/env bash
# Chooses a SPAN setting on validation seeds and reports it on fresh ones (issue 12), against the
# committed configs (configs/navigation/<scenario>.yaml).
#   experiments/navigation_select.sh NAME SETTING...
# A SETTING is one or more `key.path=value` overrides joined by '+' (so no '+' inside a value), e.g.
# span.kappa=30 or span.escape_tau=0.1+span.escape_horizon=2. The configs as they are (the working
# tree; the report names the commit and prints their span section) are always a candidate.
# Validation: 20 episodes from each seed of VAL_SEEDS (default 1000 and 1500: 2 x 20 episodes,
# disjoint from the reported ones; 20 alone cannot separate settings a few episodes apart) of every
# scenario in SCENARIOS (default sim1 sim2 dataset; dataset is the THOR replay and needs
# ../shared/data), SPAN only. The choice maximises the sum over the scenarios of the episodes that
# are successful and collision-free (simulated crowds, which react to the robot) or free of
# robot-caused collisions (the replay, whose pedestrians do not), ties to the lower summed censored
# TTG; it replaces the configs only when it beats them by at least MARGIN (default 3) episodes
# (a one-episode validation win has turned into an eight-episode loss on the report seeds). Report: 20 episodes from each seed of REPORT_SEEDS (default 0 and 500: 2 x 20 episodes),
# SPAN as committed and as chosen beside the reactive controller and ORCA (CL-RRT* is in
# results/navigation.md). Writes runs/navigation_NAME/ and results/navigation_NAME.md;
# REPORT_ONLY=1 rewrites the report from the runs already there.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
NAME=${1:?usage: navigation_select.sh NAME SETTING...}
shift
VAL_SEEDS="${VAL_SEEDS:-1000 1500}"
SCENARIOS="${SCENARIOS:-sim1 sim2 dataset}"
REPORT_SEEDS="${REPORT_SEEDS:-0 500}"
MARGIN="${MARGIN:-3}"
: "${VAL_SEEDS:?VAL_SEEDS is empty}" "${SCENARIOS:?SCENARIOS is empty}" "${REPORT_SEEDS:?REPORT_SEEDS is empty}"
OUT=runs/navigation_$NAME
cd "$ROOT"
mkdir -p results "$OUT"

navigate() {  # navigate RUN SCENARIO [key=value ...]
  local run=$1 scenario=$2
  shift 2
  [ "${REPORT_ONLY:-0}" != 1 ] || return 0
  rm -rf "$OUT/$run"
  "$BIN" navigate "configs/navigation/$scenario.yaml" video.enabled=false "$@" --run-dir "$OUT/$run" \
    > "$OUT/$run.out" 2>&1 || { tail -5 "$OUT/$run.out"; exit 1; }
}
# shellcheck source=experiments/select_lib.sh
source "$ROOT/experiments/select_lib.sh"

# The configs' predictors are trained on first use: do that here, one scenario at a time, so that
# two parallel runs below never train the same one. (A SETTING naming another predictor.artifact
# must bring it trained, as navigation_predictor.sh does.)
for scenario in $SCENARIOS; do navigate "first_$scenario" "$scenario" "methods=[span]" --episodes 1; done

settings=("" "$@")  # "" = the configs as committed
for i in "${!settings[@]}"; do
  mapfile -t o < <(overrides "${settings[$i]}")
  pids=()
  for seed in $VAL_SEEDS; do
    for scenario in $SCENARIOS; do
      navigate "val_${scenario}_${i}_s$seed" "$scenario" "methods=[span]" seed="$seed" "${o[@]}" &
      pids+=($!)
      if ((${#pids[@]} == 2)); then wait_all "${pids[@]}"; pids=(); fi
    done
  done
  wait_all "${pids[@]}"
done
read -r winner chosen < <(python3 - "$OUT" "$SCENARIOS" "$VAL_SEEDS" "${#settings[@]}" "$MARGIN" <<'PY'
import json, sys
out, scenarios, seeds, n = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), int(sys.argv[4])
margin = int(sys.argv[5])
best, configs = None, None
for i in range(n):
    ok = ttg = 0
    for s in scenarios:
        for seed in seeds:
            r = json.load(open(f"{out}/val_{s}_{i}_s{seed}/summary.json"))["span"]
            ok += r["robot_caused_collision_free" if s == "dataset" else "success_and_collision_free"]
            ttg += r["ttg_censored_mean"]
    if i == 0:
        configs = ok
    if best is None or (-ok, ttg) < best[0]:
        best = ((-ok, ttg), i)
print(best[1], best[1] if -best[0][0] >= configs + margin else 0)
PY
)
echo "chosen on validation seeds: '${settings[$chosen]}' (validation winner: '${settings[$winner]}')"
mapfile -t o < <(overrides "${settings[$winner]}")
for seed in $REPORT_SEEDS; do
  for scenario in $SCENARIOS; do
    navigate "test_${scenario}_configs_s$seed" "$scenario" "methods=[span, reactive, orca]" seed="$seed" &
    a=$!
    if [ "$winner" != 0 ]; then  # reported even when it did not clear the margin
      navigate "test_${scenario}_chosen_s$seed" "$scenario" "methods=[span]" seed="$seed" "${o[@]}" &
      wait_all "$a" "$!"
    else
      wait_all "$a"
    fi
  done
done
if [ "${REPORT_ONLY:-0}" != 1 ]; then  # the configs' commit, when the runs were made
  commit="$(git rev-parse --short HEAD 2> /dev/null || echo unknown)"
  git diff --quiet HEAD -- configs 2> /dev/null || commit="$commit with uncommitted changes to configs/"
  echo "$commit" > "$OUT/commit.txt"
fi
MARGIN="$MARGIN" COMMIT="$(cat "$OUT/commit.txt")" python3 - "$OUT" "$NAME" "$SCENARIOS" "$REPORT_SEEDS" "$VAL_SEEDS" "$chosen" "$winner" "${settings[@]}" <<'PY'
import json, os, sys
out, name, scenarios, seeds, val_seeds = sys.argv[1:6]
scenarios, seeds, val_seeds = scenarios.split(), seeds.split(), val_seeds.split()
chosen, winner, settings = int(sys.argv[6]), int(sys.argv[7]), sys.argv[8:]
label = lambda i: "configs" if i == 0 else "`" + settings[i].replace("+", " ") + "`"

def pooled(run, seeds, method):
    """Counts summed and means weighted by episodes over `seeds` (runs named RUN_s<seed>)."""
    rs = [json.load(open(f"{out}/{run}_s{s}/summary.json"))[method] for s in seeds]
    n = sum(r["episodes"] for r in rs)
    mean = lambda k: sum(r[k] * r["episodes"] for r in rs) / n
    return {"episodes": n,
            "success_and_collision_free": sum(r["success_and_collision_free"] for r in rs),
            "robot_caused_collision_free": sum(r["robot_caused_collision_free"] for r in rs),
            "ttg_censored_mean": mean("ttg_censored_mean"),
            "robot_caused_doc_mean": mean("robot_caused_doc_mean")}
val = ["| setting | " + " | ".join(f"{s}: success and collision-free / robot-caused collision-free / TTG censored (s)"
                                   for s in scenarios) + " |", "|---" * (len(scenarios) + 1) + "|"]
for i in range(len(settings)):
    cells = []
    for s in scenarios:
        r = pooled(f"val_{s}_{i}", val_seeds, "span")
        n = r["episodes"]
        cells.append(f"{r['success_and_collision_free']}/{n} / {r['robot_caused_collision_free']}/{n} / "
                     f"{r['ttg_censored_mean']:.1f}")
    val.append(f"| {label(i)}{' (chosen)' if i == chosen else ''} | " + " | ".join(cells) + " |")
test = ["| scenario | method | success and collision-free | robot-caused collision-free | TTG censored (s) | robot-caused DOC (s) |",
        "|---|---|---|---|---|---|"]
for s in scenarios:
    note = "" if winner == chosen else " (validation winner short of the margin: not adopted)"
    rows = [] if winner == 0 else [(f"SPAN, {label(winner)}{note}", pooled(f"test_{s}_chosen", seeds, "span"))]
    rows += [("SPAN, configs", pooled(f"test_{s}_configs", seeds, "span")),
             ("reactive", pooled(f"test_{s}_configs", seeds, "reactive")),
             ("ORCA", pooled(f"test_{s}_configs", seeds, "orca"))]
    for method, r in rows:
        test.append(f"| {s} | {method} | {r['success_and_collision_free']}/{r['episodes']} | "
                    f"{r['robot_caused_collision_free']}/{r['episodes']} | {r['ttg_censored_mean']:.1f} | "
                    f"{r['robot_caused_doc_mean']:.2f} |")
span = []  # the span section of the configs as run
for line in open(f"{out}/test_{scenarios[0]}_configs_s{seeds[0]}/config.yaml"):
    if line.startswith("span:"):
        span = [""]
    elif span and line.startswith("  "):
        span.append(line.strip())
    elif span:
        break
text = (f"# SPAN settings chosen on validation seeds: {name} (generated by experiments/navigation_select.sh)\n\n"
        f"configs: configs/navigation/<scenario>.yaml at {os.environ['COMMIT']}, span section "
        f"`{', '.join(span[1:])}`.\n\n"
        f"Validation: episodes from each seed of {' and '.join(val_seeds)} (pooled), SPAN only. The choice maximises the episodes that are "
        "successful and collision-free (simulated scenarios) or free of robot-caused collisions (dataset), "
        "summed over the scenarios, ties to the lower censored TTG; it replaces the configs only when it has at least "
        f"{os.environ['MARGIN']} more such episodes than they do.\n\n" + "\n".join(val) +
        f"\n\nReported: episodes from each seed of {' and '.join(seeds)} (pooled; counts out of the total).\n\n" + "\n".join(test) + "\n")
open(f"results/navigation_{name}.md", "w").write(text)
print(text)
PY
