#!/usr/bin/env bash
# CLI checks: one-line errors with non-zero exit, train -> export -> eval on a tiny synthetic run,
# resume, bench engine --json. Usage: cli_test.sh path/to/foresight
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

"$BIN" --help >/dev/null
"$BIN" data generate -o "$TMP/tracks.h5" num_tracks=30 seed=4 >/dev/null
"$BIN" data info "$TMP/tracks.h5" | grep -q "30 tracks" || fail "data info"
expect_error "num_tracks" data generate -o "$TMP/x.h5" num_tracks=-3
expect_error "not found" data info "$TMP/none.h5"
printf '0\t1\t0.0\t0.0\n10\t1\tzz\t1.0\n' > "$TMP/bad.txt"
expect_error "bad.txt:2" data convert "$TMP/bad.txt" -o "$TMP/bad.h5"

if [ "${FORESIGHT_WITH_TORCH:-1}" = "1" ] || [ "${FORESIGHT_WITH_TORCH}" = "ON" ]; then
  printf 'model: span_predictor\ntrain: {epochs: 2, learning_rat: 0.1}\n' > "$TMP/typo.yaml"
  expect_error "unknown key 'train.learning_rat'" train "$TMP/typo.yaml" --run-dir "$TMP/r0"
  expect_error "'train.epochs'" train default train.epochs=zero --run-dir "$TMP/r0"
  expect_error "'train.epochs'" train default train.epochs=0 --run-dir "$TMP/r0"
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
  "$BIN" train default "${TINY[@]}" train.epochs=3 --run-dir "$RUN" --resume >/dev/null 2>&1 && fail "resume with another config must fail"
  "$BIN" export "$RUN" >/dev/null
  "$BIN" eval default "${TINY[@]}" --run-dir "$RUN" | grep -q '"cv_nll"' || fail "eval"
  "$BIN" bench engine --artifact "$RUN/model.h5" --json --calls 500 > "$TMP/bench.json"
  for k in engine_us libtorch_us ratio train_windows_per_s; do
    grep -q "\"$k\"" "$TMP/bench.json" || fail "bench lacks $k"
  done
  head -c 2000 "$RUN/model.h5" > "$TMP/trunc.h5"
  expect_error "trunc.h5" bench engine --artifact "$TMP/trunc.h5"
  expect_error "normalisation.h5" bench engine --artifact "$RUN/normalisation.h5"
fi
echo "cli ok"
