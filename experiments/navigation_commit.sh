#!/usr/bin/env bash
# SPAN's commitment time (span.commit_time; 0 = off, the thesis): collision tests beyond t_c hold
# the predicted covariance at t_c (derivation in inference/navigation/span_controller.h), chosen on
# validation seeds and reported on fresh ones by experiments/navigation_select.sh ->
# results/navigation_commit.md. About 8 minutes on 2 cores.
#   experiments/navigation_commit.sh
set -euo pipefail
settings=()
for t in 0.5 1 2; do settings+=("span.commit_time=$t"); done
exec "$(dirname "${BASH_SOURCE[0]}")/navigation_select.sh" commit "${settings[@]}"
