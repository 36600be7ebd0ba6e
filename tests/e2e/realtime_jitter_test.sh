#!/usr/bin/env bash
# Real-rate run (label soak): >= 60 s of data paced at 30 Hz with the real-time set-up where
# permitted; reports the wake-up latency (cyclictest-style) and the budget. The budget check
# (wall clock) only with HARMOLOC_TIMING_CHECKS=1, on a quiet machine or the board: a busy one
# stretches cycles, and a test must not fail under load.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/realtime"
rm -rf "$out"; mkdir -p "$out"
"$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --loop 4 --realtime --stats "$out/stats.json" \
  --link "$out/link.bin"
check_budget "$out/stats.json"
python3 - "$out/stats.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
w = s["wakeup_latency"]
print(f"{w['count']} wake-ups: min {w['min_us']} us, mean {w['mean_us']:.1f} us, p99 {w['p99_us']} us, max {w['max_us']} us")
assert w["count"] >= 1800, "shorter than 60 s at 30 Hz"
PY
