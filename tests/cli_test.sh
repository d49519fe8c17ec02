#!/usr/bin/env bash
# CLI checks: one-line errors with non-zero exit, train -> export -> eval on a tiny synthetic run,
# resume, bench of every kind that has one; occupancy maps (train, map fuse, map info) in both builds.
# Usage: cli_test.sh path/to/foresight
set -euo pipefail
BIN="$1"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

expect_error() {  # expect_error "substring" args...
  local want="$1"; shift
  set +e
  "$BIN" "$@" >"$TMP/out" 2>"$TMP/err"
  local rc=$?
  set -e
  [ $rc -ne 0 ] || fail "expected failure: $*"
  grep -q -- "$want" "$TMP/err" || { cat "$TMP/err"; fail "error of '$*' does not mention '$want'"; }
  [ "$(grep -c 'error' "$TMP/err")" -eq 1 ] || { cat "$TMP/err"; fail "error of '$*' is not one line"; }
}

check_json() {  # check_json FILE: strict JSON, no NaN or Infinity (when python3 is there)
  if command -v python3 >/dev/null; then
    python3 -c 'import json, sys; json.load(open(sys.argv[1]), parse_constant=lambda c: sys.exit(c))' "$1" ||
      fail "$1 is not valid JSON"
  fi
}

"$BIN" --help >/dev/null
"$BIN" data generate -o "$TMP/tracks.h5" num_tracks=30 seed=4 >/dev/null
"$BIN" data info "$TMP/tracks.h5" | grep -q "30 tracks" || fail "data info"
expect_error "num_tracks" data generate -o "$TMP/x.h5" num_tracks=-3
expect_error "not found" data info "$TMP/none.h5"
printf '0\t1\t0.0\t0.0\n10\t1\tzz\t1.0\n' > "$TMP/bad.txt"
expect_error "bad.txt:2" data convert "$TMP/bad.txt" -o "$TMP/bad.h5"
printf '0\t1\t0.0\t0.0\n10\t1\t1.0\t1.0\n' > "$TMP/good.txt"
expect_error "seconds-per-step: nan" data convert "$TMP/good.txt" -o "$TMP/nan.h5" --seconds-per-step nan
mkfifo "$TMP/fifo"  # stands in for a device such as /dev/full (never touch the real ones)
expect_error "not a regular file" data convert "$TMP/good.txt" -o "$TMP/fifo"
[ -p "$TMP/fifo" ] || fail "data convert -o FIFO replaced it"

# Occupancy maps: torch-free, so in both builds.
json_number() {  # json_number FILE KEY: the number of "KEY": on its own line
  sed -n "s/^ *\"$2\": \([-+0-9.eE]*\).*/\1/p" "$1" | head -1
}
OCC="$TMP/occ"
"$BIN" train configs/occupancy/synthetic.yaml --run-dir "$OCC" >/dev/null 2>"$TMP/occ.log" || { cat "$TMP/occ.log"; fail "occupancy train"; }
for f in config.yaml model.h5 eval.json roc.csv plots/map.png; do
  [ -s "$OCC/$f" ] || fail "occupancy run dir lacks $f"
done
for k in auc precision recall artifact_bytes; do
  grep -q "\"$k\"" "$OCC/eval.json" || fail "occupancy eval.json lacks $k"
done
check_json "$OCC/eval.json"
AUC="$(json_number "$OCC/eval.json" auc)"
awk -v a="$AUC" 'BEGIN { exit !(a > 0.9) }' || fail "occupancy test AUC '$AUC' is not above 0.9"
expect_error "already holds a run (model.h5)" train configs/occupancy/synthetic.yaml --run-dir "$OCC"
# The same commands for every kind: export checks the map loads, eval recomputes the test AUC.
"$BIN" export "$OCC" | grep -q "$OCC/model.h5" || fail "occupancy export"
"$BIN" eval "$OCC" | grep -q "\"auc\": $AUC" || fail "occupancy eval"
"$BIN" kinds | grep -q "^occupancy" || fail "kinds lists occupancy"
# bench: one command for every kind, the kind from a config, a run directory or an artifact.
"$BIN" bench "$OCC" --json bench.repeats=1 bench.bhm_scans=2 bench.bhm_spacing=2 | grep -q '"fast_bhm_train_s"' ||
  fail "bench of an occupancy run"
expect_error "unknown key 'calls'" bench "$OCC" bench.calls=5
expect_error "not an artifact" bench "$OCC/model.h5"
expect_error "'navigation' has no bench step" bench configs/navigation/sim1.yaml
expect_error "nowhere.yaml: no such file" bench "$TMP/nowhere.yaml"
expect_error "not a run directory" eval "$TMP"

FUS="$TMP/fusion"
"$BIN" train configs/occupancy/synthetic_fusion.yaml --run-dir "$FUS" >/dev/null 2>"$TMP/fus.log" || { cat "$TMP/fus.log"; fail "fusion train"; }
for k in auc_single auc_fuse_once auc_fuse_once_conflation information_bytes; do
  grep -q "\"$k\"" "$FUS/eval.json" "$FUS/training_summary.json" || fail "fusion run lacks $k"
done
"$BIN" train configs/occupancy/synthetic_fusion.yaml fast_bhm.update=published --run-dir "$TMP/fus_pub" >/dev/null 2>&1 || fail "published fusion train"
grep -q '"auc_repeated"' "$TMP/fus_pub/eval.json" || fail "published fusion eval.json lacks auc_repeated"
expect_error "fast_bhm.bound_updates" train configs/occupancy/synthetic.yaml fast_bhm.bound_updates=-1 --run-dir "$TMP/occ_bad"
expect_error "fast_bhm.prior_variance" train configs/occupancy/synthetic.yaml fast_bhm.prior_variance=-1 --run-dir "$TMP/occ_bad"
check_json "$FUS/eval.json"
"$BIN" map fuse "$FUS/single.h5" "$FUS/fuse_once.h5" -o "$TMP/fused.h5" | grep -q "fused 2 maps" || fail "map fuse"
"$BIN" map fuse "$OCC/model.h5" "$FUS/single.h5" --base "$FUS/model.h5" -o "$TMP/fused_base.h5" >/dev/null || fail "map fuse --base"
"$BIN" map info "$TMP/fused.h5" | grep -q '"model_type": "occupancy.fast_bhm"' || fail "map info of a fused map"
expect_error "variance-threshold" map fuse "$FUS/single.h5" "$FUS/fuse_once.h5" -o "$TMP/nan.h5" --variance-threshold nan
expect_error "given twice" map fuse "$FUS/single.h5" "$FUS/single.h5" -o "$TMP/twice.h5"
cp "$FUS/single.h5" "$TMP/single_copy.h5"
expect_error "same bytes as input 1" map fuse "$FUS/single.h5" "$TMP/single_copy.h5" -o "$TMP/twice.h5"
expect_error "the output is also an input" map fuse "$FUS/single.h5" "$FUS/fuse_once.h5" -o "$FUS/single.h5"
mkdir -p "$TMP/a_dir"
expect_error "not a regular file" map fuse "$FUS/single.h5" "$FUS/fuse_once.h5" -o "$TMP/a_dir"
[ -d "$TMP/a_dir" ] || fail "map fuse -o DIR replaced the directory"
"$BIN" train configs/occupancy/synthetic.yaml features.spacing=0.6 --run-dir "$TMP/occ_coarse" >/dev/null 2>&1 || fail "coarse train"
expect_error "feature grid" map fuse "$OCC/model.h5" "$TMP/occ_coarse/model.h5" -o "$TMP/refused.h5"
grep -q "occ_coarse/model.h5" "$TMP/err" || fail "refused fusion does not name the map"
[ ! -e "$TMP/refused.h5" ] || fail "a refused fusion wrote its output"
"$BIN" train configs/occupancy/synthetic.yaml model=occupancy.grid --run-dir "$TMP/occ_grid" >/dev/null 2>&1 || fail "grid train"
"$BIN" map info "$TMP/occ_grid/model.h5" | grep -q '"model_type": "occupancy.grid"' || fail "map info of a grid"
expect_error "tracks.h5: not a foresight artifact" map info "$TMP/tracks.h5"

# Navigation (torch-free with the reactive and CL-RRT* baselines; SPAN needs a predictor artifact).
NAV="$TMP/nav"
"$BIN" navigate configs/navigation/sim2.yaml "methods=[reactive, cl_rrt_star]" max_time=4 video.enabled=false \
  cl_rrt_star.max_iterations=200 --episodes 1 --run-dir "$NAV" >/dev/null 2>"$TMP/nav.log" || { cat "$TMP/nav.log"; fail "navigate"; }
for f in summary.json episodes.csv paths.png map.h5 config.yaml log.txt; do
  [ -s "$NAV/$f" ] || fail "navigate output lacks $f"
done
check_json "$NAV/summary.json"
for k in reactive cl_rrt_star success_rate collision_free_rate ttg_mean doc_mean min_clearance cycle_ms_median cycle_ms_p99; do
  grep -q "\"$k\"" "$NAV/summary.json" || fail "summary.json lacks $k"
done
expect_error "unknown method 'teleport'" navigate configs/navigation/sim2.yaml "methods=[teleport]" --run-dir "$TMP/nav2"
expect_error "already holds a run (summary.json)" navigate configs/navigation/sim2.yaml --run-dir "$NAV"
expect_error "'navigation' has no export step" export "$NAV"
expect_error "'navigation' has no eval step" eval "$NAV"
expect_error "robot_goal" navigate configs/navigation/sim2.yaml "methods=[reactive]" "scenario.robot_goal=[30, 0]" --run-dir "$TMP/nav3"
expect_error "'max_time'" navigate configs/navigation/sim2.yaml max_time=3e8 --run-dir "$TMP/nav6"
expect_error "raster cells" navigate configs/navigation/sim2.yaml "scenario.extent=[-1e4, 1e4, -1e4, 1e4]" --run-dir "$TMP/nav7"
expect_error "record_duration" navigate configs/navigation/sim2.yaml predictor.record_duration=1e9 --run-dir "$TMP/nav8"
expect_error "simulation steps" navigate configs/navigation/sim2.yaml predictor.record_episodes=10000 predictor.record_duration=80000 --run-dir "$TMP/nav9"
# Manipulation (torch-free): the synthetic quickstart with the built-in Panda, and bad input.
PLAN="$TMP/plan"
"$BIN" plan default problems.synthetic_count=1 --run-dir "$PLAN" >/dev/null 2>"$TMP/plan.log" || { cat "$TMP/plan.log"; fail "plan"; }
for f in summary.json problems.csv ee_paths.png config.yaml log.txt; do
  [ -s "$PLAN/$f" ] || fail "plan output lacks $f"
done
check_json "$PLAN/summary.json"
for k in '"GFCS (1 batch)"' '"GF"' '"RRT-Connect"' success_rate ee_length cspace_length time_s ee_ldj cspace_ldj \
         candidate_statuses '"reached"' '"timeout"' '"collision"' time_median_s first_batch_sampling \
         integration_steps stalled_rollouts restarts; do
  grep -q "$k" "$PLAN/summary.json" || fail "plan summary.json lacks $k"
done
[ "$(wc -l < "$PLAN/problems.csv")" -eq 4 ] || fail "plan problems.csv: expected a header and 3 rows"
expect_error "already holds a run (summary.json)" plan default --run-dir "$PLAN"
# Two draws per problem: draw 0 is the single run's (same seed), draw 1 another seed.
"$BIN" plan default problems.synthetic_count=1 repeats=2 "methods=[{name: G, kind: gfcs}]" \
  --run-dir "$TMP/plan_repeats" >/dev/null 2>"$TMP/plan_repeats.log" || { cat "$TMP/plan_repeats.log"; fail "plan repeats"; }
[ "$(wc -l < "$TMP/plan_repeats/problems.csv")" -eq 3 ] || fail "plan repeats=2: expected a header and 2 rows"
grep -q '"repeats": 2' "$TMP/plan_repeats/summary.json" || fail "plan summary.json lacks repeats"
draw0() { awk -F, -v m="$2" '$2 == "\"" m "\"" && $NF == 0 {print $3, $4, $6, $7, $11}' "$1"; }
[ -n "$(draw0 "$PLAN/problems.csv" "GFCS (1 batch)")" ] &&
  [ "$(draw0 "$PLAN/problems.csv" "GFCS (1 batch)")" = "$(draw0 "$TMP/plan_repeats/problems.csv" G)" ] ||
  fail "plan repeats: draw 0 differs from the single run"
expect_error "repeats" plan default repeats=0 --run-dir "$TMP/plan9"
expect_error "'manipulation' has no export step" export "$PLAN"
expect_error "--problems: '9-3'" plan default --problems 9-3 --run-dir "$TMP/plan2"
expect_error "problems.source" plan default problems.source=lidar --run-dir "$TMP/plan3"
expect_error "teleport" plan default "methods=[{name: x, kind: teleport}]" --run-dir "$TMP/plan4"
expect_error "methods: 'GF' listed twice" plan default "methods=[{name: GF, kind: gf}, {name: GF, kind: gfcs}]" \
  --run-dir "$TMP/plan5"
expect_error "'GF' sets uniform_share 0.5, which only a gfcs method with sampler: learned uses" plan default \
  "methods=[{name: GF, kind: gf, uniform_share: 0.5}]" --run-dir "$TMP/plan7"
expect_error "'G' uses the nearest sampler, but energy_model (the artifact) is empty" plan default \
  "methods=[{name: G, kind: gfcs, sampler: nearest}]" --run-dir "$TMP/plan10"
expect_error "'G' sets nearest_share 0.5, which only a gfcs method with sampler: uniform or learned uses" \
  plan default "methods=[{name: G, kind: gfcs, sampler: nearest, nearest_share: 0.5}]" energy_model=x.h5 \
  --run-dir "$TMP/plan11"
expect_error "'G' sets nearest_share, but energy_model" plan default \
  "methods=[{name: G, kind: gfcs, nearest_share: 0.5}]" --run-dir "$TMP/plan12"
expect_error "'G' sets sgld_init: memory, which only a gfcs method with sampler: learned uses" plan default \
  "methods=[{name: G, kind: gfcs, sgld_init: memory}]" --run-dir "$TMP/plan13"
expect_error "uniform_share" plan default "methods=[{name: G, kind: gfcs, sampler: learned, uniform_share: 2}]" \
  energy_model=x.h5 --run-dir "$TMP/plan8"
expect_error "missing MBM problems directory" plan configs/manipulation/box.yaml problems.family=no_such_family robot=builtin \
  problems.root="$TMP" --run-dir "$TMP/plan6"
"$BIN" bench configs/manipulation/synthetic.yaml bench.repeats=1 --json | grep -q '"fabric_step_us"' ||
  fail "bench of a manipulation config"
printf 'model: occupancy.fast_bhm\nseed: 1\nseed: 2\n' > "$TMP/twice.yaml"
expect_error "key 'seed' is repeated" train "$TMP/twice.yaml" --run-dir "$TMP/r_twice"
printf '# empty\n' > "$TMP/empty.yaml"
expect_error "empty.yaml: config file is empty" train "$TMP/empty.yaml" --run-dir "$TMP/r_empty"
expect_error "unknown key 'span.kapa'" navigate configs/navigation/sim2.yaml span.kapa=3 --run-dir "$TMP/nav4"
expect_error "span_predictor" navigate configs/navigation/sim2.yaml "methods=[span]" predictor.artifact="$NAV/map.h5" \
  --episodes 1 --run-dir "$TMP/nav5"

if [ "${FORESIGHT_WITH_TORCH:-1}" = "1" ] || [ "${FORESIGHT_WITH_TORCH}" = "ON" ]; then
  printf 'model: span_predictor\ntrain: {epochs: 2, learning_rat: 0.1}\n' > "$TMP/typo.yaml"
  expect_error "unknown key 'train.learning_rat'" train "$TMP/typo.yaml" --run-dir "$TMP/r0"
  expect_error "'train.epochs'" train default train.epochs=zero --run-dir "$TMP/r0"
  expect_error "'train.epochs'" train default train.epochs=0 --run-dir "$TMP/r0"
  expect_error "predictor.train_overrides: <embedded configs/navigation/predictor.yaml>: unknown key 'network.componets'" \
    navigate configs/navigation/sim2.yaml "predictor.train_overrides=[network.componets=3]" \
    predictor.artifact="$TMP/pred/model.h5" --episodes 1 --run-dir "$TMP/nav6"
  [ ! -e "$TMP/pred/tracks.h5" ] || fail "a bad predictor.train_overrides key was found only after recording tracks"
  # train_overrides reach the predictor navigate trains, and a later change to them is refused
  # instead of silently reusing the predictor trained before.
  PRED=(predictor.artifact="$TMP/pred2/model.h5" predictor.record_episodes=1 predictor.record_duration=30)
  "$BIN" navigate configs/navigation/sim2.yaml "methods=[span]" max_time=1 video.enabled=false "${PRED[@]}" \
    'predictor.train_overrides=["train.epochs=1", "network.hidden=[8]"]' --episodes 1 --run-dir "$TMP/nav10" \
    >/dev/null 2>"$TMP/nav10.log" || { cat "$TMP/nav10.log"; fail "navigate with predictor.train_overrides"; }
  grep -q "hidden: \[8\]" "$TMP/pred2/config.yaml" || fail "predictor.train_overrides did not reach the predictor's config"
  expect_error "was trained with train.epochs = 1, not 2" navigate configs/navigation/sim2.yaml "methods=[span]" \
    "${PRED[@]}" 'predictor.train_overrides=["train.epochs=2", "network.hidden=[8]"]' --episodes 1 --run-dir "$TMP/nav11"
  expect_error "'augment.speed_scales': value 1" train default "augment.speed_scales=[0.8,1]" --run-dir "$TMP/r0"
  expect_error "augment.speed_scales" train default "augment.speed_scales=[-2]" --run-dir "$TMP/r0"
  expect_error "cannot open config file" train "$TMP/missing.yaml"
  RUN="$TMP/run"
  TINY=(data.synthetic.num_tracks=120 network.hidden=[16,16] train.epochs=2 train.batch_size=64 train.progress=lines)
  "$BIN" train default "${TINY[@]}" --run-dir "$RUN" >/dev/null 2>"$TMP/train.log" || { cat "$TMP/train.log"; fail "train"; }
  for f in config.yaml log.txt metrics.csv checkpoints/last.pt model.h5 eval.json plots/samples.png; do
    [ -s "$RUN/$f" ] || fail "run dir lacks $f"
  done
  for k in ade fde nll best_of_20_ade best_of_20_fde cv_ade cv_fde cv_nll; do
    grep -q "\"$k\"" "$RUN/eval.json" || fail "eval.json lacks $k"
  done
  for f in eval.json training_summary.json; do check_json "$RUN/$f"; done
  "$BIN" train default "${TINY[@]}" train.epochs=3 --run-dir "$RUN" --resume >/dev/null 2>&1 && fail "resume with another config must fail"
  expect_error "--resume" train default "${TINY[@]}" --run-dir "$RUN"  # a fresh start does not mix runs
  # Resuming a finished run changes nothing, and keeps the summary of the run that finished.
  cp "$RUN/training_summary.json" "$TMP/summary_before.json"
  "$BIN" train default "${TINY[@]}" --run-dir "$RUN" --resume >/dev/null 2>&1 || fail "resume of a finished run"
  cmp -s "$RUN/training_summary.json" "$TMP/summary_before.json" || fail "resuming a finished run rewrote its summary"
  # A run stopped while writing its first checkpoint (only a .tmp left) can start again, and
  # --resume without last.pt starts at epoch 1.
  mkdir -p "$TMP/tmp_only/checkpoints" && : > "$TMP/tmp_only/checkpoints/last.pt.tmp"
  "$BIN" train default "${TINY[@]}" train.epochs=1 --run-dir "$TMP/tmp_only" >/dev/null 2>&1 || fail "a run dir holding only a .tmp is refused"
  rm "$TMP/tmp_only/checkpoints/last.pt"
  "$BIN" train default "${TINY[@]}" train.epochs=1 --run-dir "$TMP/tmp_only" --resume >/dev/null 2>"$TMP/tmp_only.err" || { cat "$TMP/tmp_only.err"; fail "--resume without last.pt"; }
  grep -q "starting at epoch 1" "$TMP/tmp_only.err" "$TMP/tmp_only/log.txt" || fail "--resume without last.pt does not say it starts over"
  "$BIN" export "$RUN" >/dev/null
  "$BIN" eval "$RUN" | grep -q '"cv_nll"' || fail "eval"
  expect_error "data.synthetic.num_tracks = 120, not 100" eval "$RUN" data.synthetic.num_tracks=100
  # A loss that is non-finite in epoch 1: no checkpoint, and a summary that is still valid JSON.
  expect_error "no usable checkpoint" train default "${TINY[@]}" train.learning_rate=1e30 --run-dir "$TMP/nan_run"
  check_json "$TMP/nan_run/training_summary.json"
  grep -q '"best_val_loss": null' "$TMP/nan_run/training_summary.json" || fail "best_val_loss of no epoch is not null"
  # Ctrl-C in epoch 1 (a long one) stops cleanly, without suggesting --resume: nothing was saved.
  INT_RUN="$TMP/int_run"
  "$BIN" train default data.synthetic.num_tracks=600 network.hidden=[16,16] train.batch_size=1 train.progress=none \
    --run-dir "$INT_RUN" >/dev/null 2>"$TMP/int.err" &
  PID=$!
  for _ in $(seq 1 1200); do grep -q "windows:" "$INT_RUN/log.txt" 2>/dev/null && break; sleep 0.05; done
  kill -INT "$PID"
  set +e
  wait "$PID"
  rc=$?
  set -e
  [ $rc -ne 0 ] || fail "interrupted training exits with 0"
  grep -q "before the first checkpoint" "$TMP/int.err" || { cat "$TMP/int.err"; fail "interrupt in epoch 1"; }
  grep -q -- "--resume" "$TMP/int.err" && { cat "$TMP/int.err"; fail "interrupt in epoch 1 suggests --resume"; }
  [ ! -e "$INT_RUN/checkpoints/last.pt" ] || fail "interrupt in epoch 1 left a checkpoint"
  "$BIN" bench "$RUN" --json bench.calls=500 > "$TMP/bench.json"
  for k in engine_us libtorch_us ratio train_windows_per_s; do
    grep -q "\"$k\"" "$TMP/bench.json" || fail "bench lacks $k"
  done
  head -c 2000 "$RUN/model.h5" > "$TMP/trunc.h5"
  expect_error "trunc.h5" bench "$TMP/trunc.h5"
  expect_error "normalisation.h5" bench "$RUN/normalisation.h5"
  expect_error "only bench.key=value options apply" bench "$RUN" seed=3
  expect_error "times an exported artifact" bench configs/quickstart.yaml
  # Directional maps: crossing synthetic, 2 folds, few epochs; eval.json has the four methods.
  DIR_RUN="$TMP/dirmap"
  "$BIN" train configs/directional/crossing.yaml --run-dir "$DIR_RUN" eval.folds=2 train.epochs=2 \
    network.spatial_epochs=4 network.hidden=24 data.crossing.num_tracks=120 eval.plot_steps=20 train.progress=none \
    >/dev/null 2>"$TMP/dir.log" || { cat "$TMP/dir.log"; fail "directional train"; }
  check_json "$DIR_RUN/eval.json"
  for m in spatiotemporal spatial grid_um grid_mm; do
    grep -q "\"$m\": {\"al\": [0-9]" "$DIR_RUN/eval.json" || fail "directional eval.json lacks $m al"
  done
  [ -s "$DIR_RUN/model.h5" ] && [ -s "$DIR_RUN/plots/trajectories.png" ] || fail "directional run dir"
  expect_error "already holds a run" train configs/directional/crossing.yaml --run-dir "$DIR_RUN"
  "$BIN" export "$DIR_RUN" | grep -q "$DIR_RUN/model.h5" || fail "directional export"
  "$BIN" eval "$DIR_RUN" | grep -q '"grid_mm": {"al": [0-9]' || fail "directional eval"
  "$BIN" bench "$DIR_RUN/model.h5" --json bench.calls=200 bench.repeats=2 | grep -q engine_batch1024_us ||
    fail "bench of a directional artifact"
  # Diffeomorphic templates: a tiny synthetic run, then the step-time benchmark on its template.
  DIFF_RUN="$TMP/diffeo"
  "$BIN" train configs/diffeo/synthetic.yaml --run-dir "$DIFF_RUN" data.synthetic_demos=3 data.synthetic_points=40 \
    "data.held_out=[2]" train.epochs=2 eflow.train.epochs=2 eflow.layers=2 eval.plots=false eval.grid=2 \
    "obstacle.times=[0.002]" >/dev/null 2>"$TMP/diffeo.log" || { cat "$TMP/diffeo.log"; fail "diffeo train"; }
  check_json "$DIFF_RUN/eval.json"
  "$BIN" bench "$DIFF_RUN/models/s_curve.h5" --json bench.calls=20 bench.repeats=1 |
    grep -q engine_vs_libtorch_speedup || fail "bench of a diffeo artifact"
  # OTNet: synthetic rooms, a few epochs, then the engine benchmark on its artifact.
  OT_RUN="$TMP/otnet"
  "$BIN" train configs/otnet/synthetic.yaml --run-dir "$OT_RUN" data.synthetic_maps=12 \
    data.synthetic_trajectories=8 data.val_fraction=0.25 data.test_fraction=0.25 otnet.basis=6 \
    "otnet.hidden=[8]" train.epochs=2 eval.generated=5 eval.points=20 eval.plot_maps=2 \
    >/dev/null 2>"$TMP/otnet.log" || { cat "$TMP/otnet.log"; fail "otnet train"; }
  check_json "$OT_RUN/eval.json"
  test -f "$OT_RUN/plots/test_maps.png" || fail "otnet plots"
  expect_error "would change the map split" eval "$OT_RUN" seed=3
  "$BIN" bench "$OT_RUN" --json bench.repeats=1 bench.count=5 |
    grep -q libtorch_over_engine || fail "bench of an otnet run"
fi
echo "cli ok"
