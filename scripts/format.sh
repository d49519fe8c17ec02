#!/usr/bin/env bash
# Formats every C++ source of the repository with its .clang-format (clang-format 14, Debian).
#   scripts/format.sh          rewrite the files in place
#   scripts/format.sh --check  change nothing; list the files that differ and exit 1 if any does
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
command -v clang-format >/dev/null || { echo "clang-format is not installed (apt-get install clang-format)" >&2; exit 2; }
mapfile -t files < <(find apps core datasets experiments inference models tests training \
                       -type f \( -name '*.cc' -o -name '*.h' \) | sort)
# The files that differ from their formatted text: clang-format on batches of files, two at a time,
# each batch reporting to its own file (parallel writers would interleave their lines). A report is
# "FILE:L:C: error: code should be clang-formatted" followed by the source line and a caret line;
# any other output (a bad .clang-format, a missing file, a crash: exit status above 1) is a failure.
reports=$(mktemp -d)
trap 'rm -rf "$reports"' EXIT
printf '%s\0' "${files[@]}" |
  xargs -0 -n 50 -P 2 sh -c 'out=$(mktemp -p "$0")
    clang-format --dry-run --Werror --ferror-limit=1 "$@" >/dev/null 2>"$out"
    rc=$?; [ "$rc" -le 1 ] || echo "error: clang-format exited with status $rc" >>"$out"' "$reports" ||
  true
violation=': error: code should be clang-formatted'
mapfile -t bad < <(cat "$reports"/* | grep -F -- "$violation" | sed -E 's/:[0-9]+:[0-9]+: error: .*//' |
                     sort -u)
other=$(cat "$reports"/* | awk -v v="$violation" '
  skip > 0 { skip--; next }
  index($0, v) { skip = 2; next }
  { print }' | sort -u)
if [ -n "$other" ]; then
  printf 'clang-format failed:\n%s\n' "$other" >&2
  exit 2
fi
if [ "${1:-}" = "--check" ]; then
  if ((${#bad[@]})); then
    printf 'not formatted (run scripts/format.sh): %s\n' "${bad[@]}" >&2
    exit 1
  fi
  echo "format ok: ${#files[@]} files"
else
  # Only files that differ are rewritten (their timestamps, and so the build, stay untouched).
  ((${#bad[@]} == 0)) || clang-format -i "${bad[@]}"
fi
