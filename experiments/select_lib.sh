# Shared by the selection scripts (navigation_select.sh, span_select.sh): source it after setting
# OUT, the directory the runs write their .out logs to.

wait_all() {  # waits for every given process; when one failed, stops the others and the script
  local pid
  for pid in "$@"; do
    wait "$pid" || {
      local other
      for other in "$@"; do  # the runs' own processes too (children of background subshells)
        pkill -P "$other" 2> /dev/null || true
        kill "$other" 2> /dev/null || true
      done
      echo "a run failed (see $OUT/*.out)" >&2
      exit 1
    }
  done
}

# A SETTING is `key.path=value` overrides joined by '+': prints one override per line.
overrides() { [ -z "$1" ] || tr '+' '\n' <<< "$1"; }
