#!/usr/bin/env bash
# Fuzzes every loader (docs/robustness.md): builds the libFuzzer targets of tests/fuzz with Clang,
# AddressSanitizer and UndefinedBehaviorSanitizer (LibTorch-free, in build-fuzz/) and runs each for
# SECONDS; the LibTorch checkpoint target (built by the main build in build/) runs fuzz_main.cc's
# mutations for as long. Seeds: tests/fuzz/corpus/<target>/ plus, when ../shared/data exists, the
# first 4 KB of real files (tests/fuzz/data_seeds.txt; copied to build-fuzz/, never committed).
# Findings (crashing inputs) land in build-fuzz/fuzz/findings/<target>/; the run exits non-zero.
#   scripts/fuzz.sh [SECONDS] [TARGET ...]        default: 60 s, every target
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
PACKAGES+=(clang-14 libfuzzer-14-dev)
install_missing
SECONDS_EACH="${1:-60}"
shift || true
BUILD="$ROOT/build-fuzz"
DATA="${FORESIGHT_DATA:-$ROOT/../shared/data}"

cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
  -DFORESIGHT_WITH_TORCH=OFF -DFORESIGHT_BUILD_BENCHMARKS=OFF -DFORESIGHT_FUZZ=ON -DFORESIGHT_UNITY_BUILD=OFF > /dev/null
mapfile -t ALL < <(grep -v '^$' "$BUILD/fuzz/targets.txt")
TARGETS=("$@")
((${#TARGETS[@]})) || TARGETS=("${ALL[@]}" checkpoint)
BUILD_LIST=()
for t in "${TARGETS[@]}"; do [ "$t" = checkpoint ] || BUILD_LIST+=("fuzz_$t"); done
((${#BUILD_LIST[@]} == 0)) || cmake --build "$BUILD" -j "${FORESIGHT_JOBS:-$(nproc)}" --target "${BUILD_LIST[@]}"

# seed_corpus TARGET DIR: committed seeds + heads of real files.
seed_corpus() {
  local target="$1" dir="$2"
  rm -rf "$dir" && mkdir -p "$dir"
  cp "$ROOT/tests/fuzz/corpus/$target/"* "$dir/" 2>/dev/null || true
  [ -d "$DATA" ] || return 0
  local n=0 per_line
  while IFS=$'\t' read -r name prefix glob; do
    [ "$name" = "$target" ] || continue
    [ "$prefix" != - ] || prefix=""
    per_line=0
    for f in $DATA/$glob; do
      [ -f "$f" ] || continue
      { printf '%b' "$prefix"; head -c 4096 "$f"; } > "$dir/data_$((n++))"
      ((++per_line < 8)) || break
    done
  done < <(grep -v -e '^#' -e '^$' "$ROOT/tests/fuzz/data_seeds.txt" 2>/dev/null || true)
}

# Third-party leaks LeakSanitizer should not report (urdfdom's parser): tests/fuzz/lsan.supp.
export LSAN_OPTIONS="suppressions=$ROOT/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
STATUS=0
printf '%-24s %8s %12s  %s\n' target seconds executions result
for t in "${TARGETS[@]}"; do
  work="$BUILD/fuzz/work/$t"
  findings="$BUILD/fuzz/findings/$t"
  mkdir -p "$findings"
  seed_corpus "$t" "$work"
  log="$BUILD/fuzz/$t.log"
  if [ "$t" = checkpoint ]; then
    bin="$ROOT/build/fuzz/fuzz_checkpoint"
    if [ ! -x "$bin" ]; then
      printf '%-24s %8s %12s  %s\n' "$t" - - "skipped: build the LibTorch build first (scripts/test.sh)"
      continue
    fi
    set +e
    (cd "$findings" && "$bin" --mutate 100000000 --max-seconds "$SECONDS_EACH" --seed "$RANDOM" "$work") > "$log" 2>&1
    rc=$?
    set -e
    execs=$(grep -oE '[0-9]+ mutations ran' "$log" | grep -oE '^[0-9]+' || echo "?")
    [ $rc -eq 0 ] || cp "$findings/fuzz_last_input" "$findings/crash-$(date +%s)" 2>/dev/null || true
  else
    set +e
    "$BUILD/fuzz/fuzz_$t" -max_total_time="$SECONDS_EACH" -timeout=5 -rss_limit_mb=2048 \
      -artifact_prefix="$findings/" -print_final_stats=1 "$work" > "$log" 2>&1
    rc=$?
    set -e
    execs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo "?")
  fi
  if [ $rc -eq 0 ]; then result=ok; else result="FINDING (rc $rc): $log, inputs in $findings"; STATUS=1; fi
  printf '%-24s %8s %12s  %s\n' "$t" "$SECONDS_EACH" "$execs" "$result"
done
exit $STATUS
