#!/usr/bin/env bash
# Installs missing packages, builds Release and runs the main job on the embedded default config:
# train the SPAN pedestrian predictor on synthetic crowds, export it, evaluate it with the engine.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
install_missing
configure_and_build "$ROOT/build"
cd "$ROOT"
./build/bin/foresight train default --run-dir runs/quickstart "$@"
./build/bin/foresight bench engine --artifact runs/quickstart/model.h5
