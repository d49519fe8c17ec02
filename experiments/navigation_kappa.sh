#!/usr/bin/env bash
# SPAN's weight of the inverse time-to-collision, kappa (thesis 100; the configs hold the choice),
# and its piecewise controls (span.segments 2), chosen on validation seeds and reported on fresh ones
# by experiments/navigation_select.sh -> results/navigation_kappa.md. About 12 minutes on 2 cores.
#   experiments/navigation_kappa.sh
set -euo pipefail
settings=()
for k in ${KAPPAS:-100 30 10 3 1}; do settings+=("span.kappa=$k"); done
settings+=("span.segments=2")
exec "$(dirname "${BASH_SOURCE[0]}")/navigation_select.sh" kappa "${settings[@]}"
