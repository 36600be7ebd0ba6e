# Shared helpers for the end-to-end tests. Usage: source lib.sh BIN_DIR WORK_DIR
set -euo pipefail
BIN=$1
WORK=$2
mkdir -p "$WORK"
fail() { echo "FAIL: $*" >&2; exit 1; }
# json_number FILE KEY.PATH -> prints the number (python3 is part of Debian's base system here)
json_number() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); [d:=d[k] for k in sys.argv[2].split('.')]; print(d)" "$1" "$2"; }
# Asserts A < B for decimal numbers.
less_than() { python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < float(sys.argv[2]) else 1)" "$1" "$2" || fail "$3: $1 is not below $2"; }
# make_dataset N DIR: a copy of the test run cut to its first N frames (encoder log kept whole).
make_dataset() {
  local n=$1 d=$2
  rm -rf "$d"; mkdir -p "$d/frames"
  cp "$WORK/test/metadata.toml" "$WORK/test/encoders.log" "$d/"
  head -n $((n + 1)) "$WORK/test/frames.csv" > "$d/frames.csv"
  tail -n +2 "$d/frames.csv" | cut -d, -f2 | while read -r f; do cp "$WORK/test/$f" "$d/$f"; done
}

# The run's budget report; the 15 ms budget checked only with HARMOLOC_TIMING_CHECKS=1 (a quiet
# machine, the board): a busy machine stretches wall-clock cycles, and a test must not fail under
# load. Otherwise the run must fit a budget no load reaches (1 s a cycle).
#   check_budget STATS_JSON
check_budget() {
  if [ "${HARMOLOC_TIMING_CHECKS:-0}" = 1 ]; then
    "$BIN/harmoloc-budget" "$1" --check
  else
    "$BIN/harmoloc-budget" "$1"
    "$BIN/harmoloc-budget" "$1" --budget-ms 1000 --check > /dev/null
  fi
}
