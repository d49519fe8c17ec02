#!/usr/bin/env bash
# A predictor variant for SPAN navigation (issue 12), chosen per scenario on validation seeds and
# reported on fresh ones by experiments/navigation_select.sh -> results/navigation_predictor_select_<scenario>.md.
#   experiments/navigation_predictor.sh NAME OVERRIDE...      e.g. r3 network.components=3
# For each scenario of SCENARIOS (default sim1 sim2 dataset), the variant is the scenario's
# predictor (its predictor.train_config and predictor.train_overrides) with the OVERRIDEs added,
# plus THOR_OVERRIDES (space-separated) for dataset, the THOR replay, whose predictor learns from
# 126 tracklets (e.g. more epochs). It is trained into runs/navigation_predictor_<scenario>_NAME/
# first, so that the parallel validation runs find it, then set through predictor.artifact and
# predictor.train_overrides. The predictor's own held-out figures are in that run directory.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
NAME=${1:?usage: navigation_predictor.sh NAME OVERRIDE...}
shift
(($# > 0)) || { echo "navigation_predictor.sh: no OVERRIDE given" >&2; exit 1; }
cd "$ROOT"
for scenario in ${SCENARIOS:-sim1 sim2 dataset}; do
  o=("$@")
  if [ "$scenario" = dataset ]; then
    set -f  # no globbing of [..] in the overrides
    # shellcheck disable=SC2206  # THOR_OVERRIDES is a space-separated list
    o+=(${THOR_OVERRIDES:-})
    set +f
  fi
  name=$([ "$scenario" = dataset ] && echo thor || echo "$scenario")
  artifact="runs/navigation_predictor_${name}_$NAME/model.h5"
  # The scenario's own overrides first, then the variant's, as a YAML list of quoted strings.
  list=$(python3 - "configs/navigation/$scenario.yaml" "${o[@]}" << 'PY'
import json, sys, yaml
own = (yaml.safe_load(open(sys.argv[1])).get("predictor") or {}).get("train_overrides") or []
print(json.dumps(list(own) + sys.argv[2:]))
PY
)
  if [ ! -f "$artifact" ] && [ "${REPORT_ONLY:-0}" != 1 ]; then
    mkdir -p "$(dirname "$artifact")"
    "$BIN" navigate "configs/navigation/$scenario.yaml" "methods=[span]" video.enabled=false \
      "predictor.artifact=$artifact" "predictor.train_overrides=$list" --episodes 1 \
      --run-dir "runs/navigation_predictor_${name}_$NAME.first" > "runs/navigation_predictor_${name}_$NAME.out" 2>&1 ||
      { tail -5 "runs/navigation_predictor_${name}_$NAME.out"; exit 1; }
  fi
  SCENARIOS=$scenario "$ROOT/experiments/navigation_select.sh" "predictor_select_$scenario" \
    "predictor.artifact=$artifact+predictor.train_overrides=$list"
done
