#!/usr/bin/env bash
# A run recorded with 16-bit encoder counters that wrap within seconds: odometry must not jump.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/wrap"
mkdir -p "$out"
grep -q 'counter_bits = 16' "$WORK/wrap16/metadata.toml" || fail "wrap16 dataset is not 16-bit"
"$BIN/harmoloc" --dataset "$WORK/wrap16" --map "$WORK/tiny.hmap" --trajectory "$out/est.tum" --stats "$out/stats.json" --quiet
"$BIN/harmoloc-report" --truth "$WORK/wrap16/groundtruth.tum" --estimate "$out/est.tum" --out "$out/report" --skip-initial 3 > /dev/null
rmse=$(python3 -c "import json,sys; d=json.load(open(sys.argv[1]))['estimate']; print(d.get('after_convergence', d['all'])['rmse_position_cm'])" "$out/report/summary.json")
echo "fused RMSE across 16-bit wraps: $rmse cm"
less_than "$rmse" 8 "position RMSE (cm) with wrapping counters"
