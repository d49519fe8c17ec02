#!/usr/bin/env bash
# Installs missing packages, builds Release and runs the main job on the embedded defaults:
# 1. the navigation quickstart (`foresight navigate default` = configs/navigation/sim1.yaml): train
#    the SPAN predictor on simulated crowd tracks, build the map, navigate sim1 with SPAN and the
#    reactive and CL-RRT* baselines, write summary.json, paths.png and a video;
# 2. the SPAN predictor quickstart on synthetic tracks (train, export, engine eval and bench);
# 3. Fast-BHM occupancy maps of a simulated floor plan, fused between two robots;
# 4. the manipulation quickstart (`foresight plan default` = configs/manipulation/synthetic.yaml):
#    GFCS, the geometric fabric and RRT-Connect on generated scenes with the built-in Panda.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
install_missing
configure_and_build "$ROOT/build"
cd "$ROOT"
# The navigation quickstart. The predictor (runs/navigation_predictor_sim1) is trained once and
# reused by later runs; delete that directory to retrain it.
rm -rf runs/navigate_quickstart
./build/bin/foresight navigate default --run-dir runs/navigate_quickstart --episodes 3
# Each run of the main job starts afresh (train refuses to start a new run in a directory that
# holds one), unless it continues the last one with --resume.
[[ " $* " == *" --resume "* ]] || rm -rf runs/quickstart
./build/bin/foresight train default --run-dir runs/quickstart "$@"
./build/bin/foresight bench runs/quickstart
# Occupancy maps on the simulated two-robot floor plan: Fast-BHMs, fused once and repeatedly.
rm -rf runs/occupancy_synthetic_fusion
./build/bin/foresight train configs/occupancy/synthetic_fusion.yaml --run-dir runs/occupancy_synthetic_fusion
# Manipulation (thesis ch 9): GFCS, the single-attractor fabric and RRT-Connect on synthetic scenes.
rm -rf runs/plan_quickstart
./build/bin/foresight plan default --run-dir runs/plan_quickstart
./build/bin/foresight bench configs/manipulation/synthetic.yaml
# Self-supervised GFCS (thesis ch 9): the loop on 12 generated scenes, then the learned sampler
# against the uniform one on 6 others (runs/gfcs_quickstart/eval.json).
rm -rf runs/gfcs_quickstart
./build/bin/foresight train configs/gfcs/synthetic.yaml --run-dir runs/gfcs_quickstart
# Diffeomorphic templates (thesis ch 8): a synthetic S-shaped family, EFlow in the same run, an
# obstacle on the demonstrations (runs/diffeo_quickstart/eval.json, plots/s_curve.png), then the
# step-time benchmark.
rm -rf runs/diffeo_quickstart
./build/bin/foresight train configs/diffeo/synthetic.yaml --run-dir runs/diffeo_quickstart
./build/bin/foresight bench runs/diffeo_quickstart/models/s_curve.h5
# OTNet (thesis ch 6): synthetic rooms and corridors, trajectories generated on unseen maps against
# k-NN and the mean trajectory (runs/otnet_quickstart/eval.json, plots/test_maps.png), then the
# encode-and-generate benchmark.
rm -rf runs/otnet_quickstart
./build/bin/foresight train configs/otnet/synthetic.yaml --run-dir runs/otnet_quickstart
./build/bin/foresight bench runs/otnet_quickstart
# Structurally constrained prediction (thesis ch 7): synthetic scenes with maps; the mixture prior,
# KTM, constant velocity and the naive network, and the prior projected onto the collision chance
# constraint, quadratures chosen on validation windows and every result checked
# (runs/constrained_quickstart/eval.json, tracks.csv, plots/window_*.png; about 1.5 min).
rm -rf runs/constrained_quickstart
./build/bin/foresight train configs/constrained/synthetic.yaml --run-dir runs/constrained_quickstart
