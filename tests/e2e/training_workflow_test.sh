#!/usr/bin/env bash
# The training workflow of docs/training.md as a robot owner runs it: record the area log of a run
# with the firmware before any map exists, train from the log, the encoder log and the labels,
# replay with the new map. The map must equal the one trained from the frames, the fixes must be
# accurate, and every mismatch between log, config and map is refused with one line.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/training"
rm -rf "$out"; mkdir -p "$out"
"$BIN/harmoloc" --dataset "$WORK/train" --record-areas "$out/areas.csv" --stats "$out/rec.json" --quiet > "$out/rec.txt"
frames=$(($(wc -l < "$WORK/train/frames.csv") - 1))
[ "$(($(wc -l < "$out/areas.csv") - 3))" -eq "$frames" ] || fail "area log has not one line per frame"
[ "$(json_number "$out/rec.json" localizer.fixes)" -eq 0 ] || fail "a run without a map used fixes"
# An area log carries no robot geometry: the camera's offset ahead of the axle comes from the
# robot (here the dataset's metadata), as the wheel geometry comes from the config.
offset=$(sed -n 's/^forward_offset_m = //p' "$WORK/train/metadata.toml")
[ -n "$offset" ] || fail "the simulator's metadata.toml gives no camera.forward_offset_m"
"$BIN/harmoloc-train" --areas "$out/areas.csv" --encoders "$WORK/train/encoders.log" --labels "$WORK/train/labels.tum" --camera-forward-m "$offset" --out "$out/from_areas.hmap" > "$out/train.txt"
grep -q "seen from the camera's place, 100 mm ahead of the axle" "$out/train.txt" || fail "harmoloc-train did not map the bearings from the camera's place"
! grep -q "^column gain" "$out/train.txt" || fail "the trainer measured the column gain unasked"
# --column-gain (experimental, map format 13): the gain measured on the run's passes and said.
"$BIN/harmoloc-train" --areas "$out/areas.csv" --encoders "$WORK/train/encoders.log" --labels "$WORK/train/labels.tum" --camera-forward-m "$offset" --column-gain --out "$out/gain.hmap" > "$out/gain.txt"
grep -q "^column gain   a board's area x [0-9.]* a quarter frame from the centre, x [0-9.]* at the side ([0-9]* boards in [0-9]* pairs" "$out/gain.txt" || fail "the trainer did not measure the area's gain by column: $(grep '^column' "$out/gain.txt")"
cat "$out/train.txt"
cmp "$out/from_areas.hmap" "$WORK/tiny.hmap" || fail "the map trained from the area log differs from the one trained from the frames"
grep -q "^boards  *start with" "$out/train.txt" || fail "the trainer did not say which boards it started from"
grep -q "^known place" "$out/train.txt" || fail "the trainer did not report the known-place bound"

# Replays the test run with map $1 and holds its harmonic fixes' MSE per axis under 10 cm^2 ($2:
# what the map is, for the messages).
replay_fixes() {
  local name; name=$(basename "$1" .hmap)
  "$BIN/harmoloc" --dataset "$WORK/test" --map "$1" --fixes "$out/$name-fixes.tum" --quiet > /dev/null
  "$BIN/harmoloc-report" --truth "$WORK/test/groundtruth.tum" --estimate "$out/$name-fixes.tum" --out "$out/$name-report" > /dev/null
  mse() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['estimate']['all'][sys.argv[2]])" "$out/$name-report/summary.json" "$1"; }
  echo "harmonic fixes on the test run, $2: MSE x $(mse mse_x_cm2) cm^2, y $(mse mse_y_cm2) cm^2"
  less_than "$(mse mse_x_cm2)" 10 "harmonic fix MSE x, $2 (cm^2)"
  less_than "$(mse mse_y_cm2)" 10 "harmonic fix MSE y, $2 (cm^2)"
}
replay_fixes "$out/from_areas.hmap" "map from the area log"
# The firmware takes the column gain out of every frame as the trainer took it out of the samples:
# the map with it localizes the test run as well.
replay_fixes "$out/gain.hmap" "with --column-gain"

# Mismatches: a log recorded with other thresholds, and a map used with another config.
printf '[[board]]\nname = "red"\nhue_deg = [0, 20]\n' > "$out/other.toml"
if "$BIN/harmoloc-train" --areas "$out/areas.csv" --labels "$WORK/train/labels.tum" --config "$out/other.toml" \
  --out "$out/x.hmap" > /dev/null 2> "$out/err.txt"; then fail "trained a log with other thresholds"; fi
[ "$(wc -l < "$out/err.txt")" -eq 1 ] || fail "not one line: $(cat "$out/err.txt")"
grep -q "boards but the config has 1\|other colour thresholds" "$out/err.txt" || fail "unclear: $(cat "$out/err.txt")"
if "$BIN/harmoloc" --dataset "$WORK/test" --map "$out/from_areas.hmap" --config "$out/other.toml" --quiet > /dev/null 2> "$out/err.txt"; then
  fail "the firmware ran a map trained with other thresholds"
fi
[ "$(wc -l < "$out/err.txt")" -eq 1 ] && grep -q "retrain" "$out/err.txt" || fail "unclear: $(cat "$out/err.txt")"
if "$BIN/harmoloc" --dataset "$WORK/test" --quiet > /dev/null 2> "$out/err.txt"; then fail "ran without a map"; fi
grep -q -- "--record" "$out/err.txt" || fail "no hint at --record: $(cat "$out/err.txt")"
# Labels on another clock: an external reference 0.3 s ahead of the robot. Without the offset the
# last label falls outside the run and is refused; --label-offset -0.3 puts them back; 'auto'
# finds the offset from the wheel odometry (within 30 ms) and says so.
python3 - "$WORK/train/labels.tum" "$out/labels_ahead.tum" 0.3 <<'PY'
import sys
with open(sys.argv[2], 'w') as out:
    for l in open(sys.argv[1]):
        f = l.split()
        if f: f[0] = '%.9f' % (float(f[0]) + float(sys.argv[3])); out.write(' '.join(f) + '\n')
PY
if "$BIN/harmoloc-train" --dataset "$WORK/train" --labels "$out/labels_ahead.tum" --out "$out/x.hmap" \
  > /dev/null 2> "$out/err.txt"; then fail "trained on labels 0.3 s off the run without an offset"; fi
"$BIN/harmoloc-train" --dataset "$WORK/train" --labels "$out/labels_ahead.tum" --label-offset -0.3 \
  --out "$out/offset.hmap" > "$out/offset.txt" || fail "--label-offset -0.3 refused"
grep -q 'time offset -0.300 s (--label-offset)' "$out/offset.txt" || fail "the offset is not said"
"$BIN/harmoloc-train" --dataset "$WORK/train" --labels "$out/labels_ahead.tum" --label-offset auto \
  --out "$out/auto.hmap" > "$out/auto.txt" || fail "--label-offset auto refused"
found=$(sed -n 's/^labels  *time offset \([-+0-9.]*\) s +- .*estimated.*/\1/p' "$out/auto.txt")
[ -n "$found" ] || fail "no estimated offset said: $(head -3 "$out/auto.txt")"
python3 -c "import sys; sys.exit(0 if abs(float(sys.argv[1]) + 0.3) <= 0.03 else 1)" "$found" \
  || fail "estimated offset $found s, the labels are 0.3 s ahead"
grep -q '^labels  *heading ' "$out/auto.txt" || fail "whether heading is used is not said"
echo "ok  labels 0.3 s ahead: refused without an offset, trained with --label-offset -0.3 and with auto ($found s)"
# Without odometry a label names the frame nearest its time within --label-tolerance-ms.
python3 - "$WORK/train/labels.tum" "$out/labels_2ms.tum" 0.002 <<'PY'
import sys
with open(sys.argv[2], 'w') as out:
    for l in open(sys.argv[1]):
        f = l.split()
        if f: f[0] = '%.9f' % (float(f[0]) + float(sys.argv[3])); out.write(' '.join(f) + '\n')
PY
if "$BIN/harmoloc-train" --dataset "$WORK/train" --labels "$out/labels_2ms.tum" --no-odometry \
  --out "$out/x.hmap" > /dev/null 2> "$out/err.txt"; then fail "labels 2 ms off matched with 0.5 ms tolerance"; fi
grep -q 'label-tolerance-ms' "$out/err.txt" || fail "no hint at --label-tolerance-ms: $(cat "$out/err.txt")"
"$BIN/harmoloc-train" --dataset "$WORK/train" --labels "$out/labels_2ms.tum" --no-odometry \
  --label-tolerance-ms 5 --out "$out/tol.hmap" > "$out/tol.txt" || fail "--label-tolerance-ms 5 refused"
grep -q 'unmatched 0' "$out/tol.txt" || fail "labels unmatched with 5 ms tolerance: $(grep matched "$out/tol.txt")"
echo "training workflow ok"
