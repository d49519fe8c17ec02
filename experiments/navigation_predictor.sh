#!/usr/bin/env bash
# A predictor variant for SPAN navigation (issue 12), chosen per scenario on validation seeds and
# reported on fresh ones by experiments/navigation_select.sh -> results/navigation_predictor_<scenario>.md.
#   experiments/navigation_predictor.sh NAME OVERRIDE...      e.g. r3 network.components=3
# For each scenario of SCENARIOS (default sim1 sim2 dataset), the variant is the scenario's
# predictor config with the OVERRIDEs (plus THOR_OVERRIDES for dataset, the THOR replay, whose
# predictor learns from 126 tracklets: e.g. more epochs), trained into
# runs/navigation_predictor_<scenario>_NAME/ first (so the parallel validation runs find it), then
# set through predictor.artifact and predictor.train_overrides. The choice of the predictor
# (validation runs, and its held-out ADE / NLL / calibration) is in the runs' directories.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${FORESIGHT_BIN:-$ROOT/build/bin/foresight}"
NAME=${1:?usage: navigation_predictor.sh NAME OVERRIDE...}
shift
(($# > 0)) || { echo "navigation_predictor.sh: no OVERRIDE given" >&2; exit 1; }
cd "$ROOT"
join() { local IFS=,; echo "[$*]"; }
for scenario in ${SCENARIOS:-sim1 sim2 dataset}; do
  o=("$@")
  # shellcheck disable=SC2206  # THOR_OVERRIDES is a space-separated list
  [ "$scenario" != dataset ] || o+=(${THOR_OVERRIDES:-})
  name=$([ "$scenario" = dataset ] && echo thor || echo "$scenario")
  artifact="runs/navigation_predictor_${name}_$NAME/model.h5"
  setting="predictor.artifact=$artifact+predictor.train_overrides=$(join "${o[@]}")"
  if [ ! -f "$artifact" ] && [ "${REPORT_ONLY:-0}" != 1 ]; then
    mkdir -p "$(dirname "$artifact")"
    "$BIN" navigate "configs/navigation/$scenario.yaml" "methods=[span]" video.enabled=false \
      "predictor.artifact=$artifact" "predictor.train_overrides=$(join "${o[@]}")" --episodes 1 \
      --run-dir "runs/navigation_predictor_${name}_$NAME.first" > "runs/navigation_predictor_${name}_$NAME.out" 2>&1 ||
      { tail -5 "runs/navigation_predictor_${name}_$NAME.out"; exit 1; }
  fi
  SCENARIOS=$scenario "$ROOT/experiments/navigation_select.sh" "predictor_$scenario" "$setting"
done
