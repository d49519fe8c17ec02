#!/usr/bin/env bash
# Fault tests of the command line (docs/robustness.md), LibTorch build:
#  - kill -9 at random points of training: nothing half-written where a valid file is expected
#    (every checkpoint that exists loads), and `--resume` gives the same artifact and eval.json, bit
#    for bit, as an uninterrupted run;
#  - full disk (a file-size limit: every write past it fails as on a full disk) during training,
#    export and `data convert`: a one-line error, a non-zero exit, no half-written result;
#  - read-only run directories: a one-line error naming the directory (skipped with a message when
#    the test cannot make a directory read-only: root without mount permission).
# Usage: fault_test.sh path/to/foresight [ROUNDS]
set -euo pipefail
BIN="$(realpath "$1")"
ROUNDS="${2:-3}"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
cd "$TMP"
fail() { echo "FAIL: $*" >&2; exit 1; }
# expect_one_line_error NEEDLE CMD...: the command exits non-zero and its last stderr line (the
# error) contains NEEDLE and is one line starting with "foresight: error:".
expect_one_line_error() {
  local needle="$1"; shift
  set +e
  "$@" > "$TMP/out" 2> "$TMP/err"
  local rc=$?
  set -e
  [ $rc -ne 0 ] || fail "exit 0 from: $*"
  [ $rc -lt 128 ] || { cat "$TMP/err"; fail "killed by a signal ($rc): $*"; }
  local last
  last="$(tail -n 1 "$TMP/err")"
  [[ "$last" == "foresight: error: "* ]] || { cat "$TMP/err"; fail "no one-line error from: $*"; }
  [[ "$last" == *"$needle"* ]] || { cat "$TMP/err"; fail "error does not name '$needle': $*"; }
}

TINY=(data.synthetic.num_tracks=300 network.hidden=[16,16] train.epochs=8 train.batch_size=32
      train.patience=3 train.progress=none)
"$BIN" train default "${TINY[@]}" --run-dir straight > /dev/null 2>&1 || fail "uninterrupted run"

# ---- kill -9 at random points, then resume ------------------------------------------------
for round in $(seq 1 "$ROUNDS"); do
  run="killed_$round"
  # A random epoch (1..5) and a random moment inside the next one.
  epoch=$((1 + RANDOM % 5))
  delay="0.$(printf '%02d' $((RANDOM % 30)))"
  "$BIN" train default "${TINY[@]}" --run-dir "$run" > /dev/null 2>&1 &
  pid=$!
  for _ in $(seq 1 600); do
    lines=$(grep -c '' "$run/metrics.csv" 2>/dev/null || true)
    [ "${lines:-0}" -gt "$epoch" ] && break  # the header and `epoch` rows
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.02
  done
  sleep "$delay"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  # Whatever exists under a final name is complete: every checkpoint loads (export reads best.pt).
  if [ ! -e "$run/checkpoints/last.pt" ]; then
    echo "round $round: killed before the first checkpoint (epoch $epoch + ${delay}s); starting afresh"
    rm -rf "$run"
    "$BIN" train default "${TINY[@]}" --run-dir "$run" > /dev/null 2>&1 || fail "fresh run after an early kill"
  else
    "$BIN" train default "${TINY[@]}" --run-dir "$run" --resume > /dev/null 2> "$TMP/resume.err" ||
      { cat "$TMP/resume.err"; fail "resume after kill -9 at epoch $epoch + ${delay}s"; }
  fi
  cmp -s straight/model.h5 "$run/model.h5" || fail "round $round: resumed artifact differs (kill at epoch $epoch + ${delay}s)"
  cmp -s straight/eval.json "$run/eval.json" || fail "round $round: resumed eval.json differs"
  cmp -s straight/metrics.csv "$run/metrics.csv" || true  # seconds columns differ; rows are checked below
  [ "$(cut -d, -f1-4 straight/metrics.csv)" = "$(cut -d, -f1-4 "$run/metrics.csv")" ] ||
    fail "round $round: resumed metrics rows differ"
  echo "round $round: kill -9 at epoch $epoch + ${delay}s, resumed: same model.h5, eval.json, metrics"
done

# ---- full disk (RLIMIT_FSIZE with SIGXFSZ ignored: writes past the limit fail with EFBIG, as they
# would with ENOSPC on a full disk) ---------------------------------------------------------------
limited() { (ulimit -f "$LIMIT_KB"; trap '' XFSZ; "$@"); }
# training: the first checkpoint does not fit
LIMIT_KB=16 expect_one_line_error "cannot write" limited "$BIN" train default "${TINY[@]}" --run-dir full_train
[ ! -e full_train/model.h5 ] || fail "a full disk during training left a model.h5"
[ -z "$(find full_train -name '*.tmp')" ] || fail "a full disk left temporary files: $(find full_train -name '*.tmp')"
[ ! -e full_train/checkpoints/last.pt ] || fail "a checkpoint that did not fit exists"
# export of a finished run: no partial artifact
cp -r straight export_full && rm -f export_full/model.h5
LIMIT_KB=4 expect_one_line_error "model.h5" limited "$BIN" export export_full
[ ! -e export_full/model.h5 ] || fail "a failed export left model.h5"
# data convert: a track store that does not fit is not left behind
awk 'BEGIN { for (f = 0; f < 400; f += 10) for (p = 1; p <= 5; p++) printf "%d\t%d\t%.3f\t%.3f\n", f, p, p + f / 100, f / 50 }' > tracks.txt
"$BIN" data convert tracks.txt -o whole.h5 --seconds-per-step 0.4 > /dev/null 2>&1 || fail "data convert"
LIMIT_KB=4 expect_one_line_error "part.h5" limited "$BIN" data convert tracks.txt -o part.h5 --seconds-per-step 0.4
[ ! -e part.h5 ] || fail "a failed data convert left part.h5"
[ -z "$(find . -maxdepth 1 -name 'part.h5*')" ] || fail "a failed data convert left $(find . -maxdepth 1 -name 'part.h5*')"
echo "full disk: training, export and data convert stop with one line and leave nothing half-written"

# ---- read-only run directories -----------------------------------------------------------------
# make_read_only DIR: DIR (existing, with its contents) becomes read-only; returns 1 when the test
# cannot do that (root, who writes anywhere, without permission to bind-mount).
RO_MOUNTS=()
make_read_only() {
  if [ "$(id -u)" -ne 0 ]; then
    chmod -R a-w "$1"
  elif mount --bind "$1" "$1" 2>/dev/null && mount -o remount,ro,bind "$1" 2>/dev/null; then
    RO_MOUNTS+=("$1")
  else
    umount "$1" 2>/dev/null || true
    return 1
  fi
}
trap 'for m in "${RO_MOUNTS[@]}"; do umount "$m" 2>/dev/null || true; done; chmod -R u+w "$TMP" 2>/dev/null; rm -rf "$TMP"' EXIT
mkdir -p ro_parent
cp -r straight ro_run && rm -f ro_run/model.h5
if make_read_only ro_parent && make_read_only ro_run; then
  expect_one_line_error "ro_parent/run" "$BIN" train default "${TINY[@]}" --run-dir ro_parent/run
  expect_one_line_error "ro_run" "$BIN" export ro_run
  expect_one_line_error "ro_run" "$BIN" eval ro_run
  echo "read-only: train, export and eval stop with one line naming the directory"
else
  echo "skipped: read-only directories (root without permission to bind-mount read-only)"
fi
echo "fault tests passed"
