#!/usr/bin/env bash
# Installs missing packages, builds Release and runs the main job on the embedded default config:
# train the SPAN pedestrian predictor on synthetic crowds, export it, evaluate it with the engine.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
install_missing
configure_and_build "$ROOT/build"
cd "$ROOT"
# Each run of the main job starts afresh (train refuses to start a new run in a directory that
# holds one), unless it continues the last one with --resume.
[[ " $* " == *" --resume "* ]] || rm -rf runs/quickstart
./build/bin/foresight train default --run-dir runs/quickstart "$@"
./build/bin/foresight bench engine --artifact runs/quickstart/model.h5
# Occupancy maps on the simulated two-robot floor plan: Fast-BHMs, fused once and repeatedly.
rm -rf runs/occupancy_synthetic_fusion
./build/bin/foresight train configs/occupancy/synthetic_fusion.yaml --run-dir runs/occupancy_synthetic_fusion
