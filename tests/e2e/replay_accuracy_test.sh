#!/usr/bin/env bash
# Replays the test run through the firmware's cycle and checks the fused pose against ground
# truth (bounds justified in docs/testing.md).
source "$(dirname "$0")/lib.sh" "$@"
RMSE_BOUND_CM=${3:-8}
HEADING_BOUND_DEG=${4:-10}
out="$WORK/accuracy"
mkdir -p "$out"
"$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --trajectory "$out/est.tum" --fixes "$out/fixes.tum" \
  --link "$out/link.bin" --stats "$out/stats.json" --quiet
"$BIN/harmoloc-report" --truth "$WORK/test/groundtruth.tum" --estimate "$out/est.tum" --fixes "$out/fixes.tum" \
  --stats "$out/stats.json" --out "$out/report" --skip-initial 3
s="$out/report/summary.json"
cat "$out/report/summary.txt"
frames=$(json_number "$out/stats.json" frames)
[ "$frames" -eq "$(($(wc -l < "$WORK/test/frames.csv") - 1))" ] || fail "cycle saw $frames frames"
summary() { python3 -c "import json,sys; d=json.load(open(sys.argv[1]))[sys.argv[2]]; print(d.get('after_convergence', d['all'])[sys.argv[3]])" "$s" "$1" "$2"; }
rmse=$(summary estimate rmse_position_cm)
fix_rmse=$(summary fixes rmse_position_cm)
heading=$(summary estimate rmse_heading_deg)
echo "fused RMSE $rmse cm, harmonic fixes RMSE $fix_rmse cm, heading RMSE $heading deg (after the first 3 s)"
less_than "$rmse" "$RMSE_BOUND_CM" "fused position RMSE (cm) after convergence"
less_than "$heading" "$HEADING_BOUND_DEG" "fused heading RMSE (deg) after convergence"
[ "$(json_number "$out/stats.json" overruns)" -eq 0 ] || fail "overruns on the host"
for f in index.html trajectory.svg error.svg timing.svg; do test -s "$out/report/$f" || fail "report lacks $f"; done
