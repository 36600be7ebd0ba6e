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
"$BIN/harmoloc-train" --areas "$out/areas.csv" --encoders "$WORK/train/encoders.log" --labels "$WORK/train/labels.tum" --out "$out/from_areas.hmap" > "$out/train.txt"
cat "$out/train.txt"
cmp "$out/from_areas.hmap" "$WORK/tiny.hmap" || fail "the map trained from the area log differs from the one trained from the frames"
grep -q "^boards  *start with" "$out/train.txt" || fail "the trainer did not say which boards it started from"
grep -q "^known place" "$out/train.txt" || fail "the trainer did not report the known-place bound"

"$BIN/harmoloc" --dataset "$WORK/test" --map "$out/from_areas.hmap" --fixes "$out/fixes.tum" --quiet > /dev/null
"$BIN/harmoloc-report" --truth "$WORK/test/groundtruth.tum" --estimate "$out/fixes.tum" --out "$out/report" > /dev/null
mse() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['estimate']['all'][sys.argv[2]])" "$out/report/summary.json" "$1"; }
echo "harmonic fixes on the test run: MSE x $(mse mse_x_cm2) cm^2, y $(mse mse_y_cm2) cm^2"
less_than "$(mse mse_x_cm2)" 10 "harmonic fix MSE x (cm^2)"
less_than "$(mse mse_y_cm2)" 10 "harmonic fix MSE y (cm^2)"

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
grep -q "record-areas" "$out/err.txt" || fail "no hint at --record-areas: $(cat "$out/err.txt")"
echo "training workflow ok"
