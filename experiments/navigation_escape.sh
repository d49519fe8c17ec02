#!/usr/bin/env bash
# SPAN's escape fallback (span.escape_tau, span.escape_horizon; escape_tau 0 = off, the thesis),
# chosen on validation seeds and reported on fresh ones by experiments/navigation_select.sh ->
# results/navigation_escape.md. About 12 minutes on 2 cores.
#   experiments/navigation_escape.sh
set -euo pipefail
settings=("span.escape_tau=0")
for tau in 0.1 0.5; do
  for window in 0.5 1 2; do settings+=("span.escape_tau=$tau+span.escape_horizon=$window"); done
done
exec "$(dirname "${BASH_SOURCE[0]}")/navigation_select.sh" escape "${settings[@]}"
