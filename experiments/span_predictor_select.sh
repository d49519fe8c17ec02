#!/usr/bin/env bash
# The SPAN predictor settings of configs/span/eth_ucy_*.yaml, chosen by scene-held-out validation
# (experiments/span_select.sh) -> results/span_select_predictor.md: predicting the residual to
# constant velocity, with mirrored or speed-scaled training copies, and the mixture head (R = 3).
# About 50 minutes on 2 cores; REPORT_ONLY=1 rewrites the report from the runs.
#   experiments/span_predictor_select.sh
set -euo pipefail
R=network.residual_to_constant_velocity=true
S="augment.speed_scales=[0.75,1.33]"
exec "$(dirname "${BASH_SOURCE[0]}")/span_select.sh" predictor "$R" "$R+augment.mirror=true" "$R+$S" \
  "$R+$S+augment.mirror=true" network.components=3 "$R+network.components=3"
