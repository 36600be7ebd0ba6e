#!/usr/bin/env bash
# harmoloc --record DIR (docs/dataset-format.md, "Recording on the robot"): the training run is
# recorded by the firmware itself, without a map, into a dataset folder that harmoloc-train takes
# and the host board replays with no conversion. The map trained from the recording must localise
# the test run as well as the map trained from the original (within 1 cm RMS, or 1.5x). With a
# map the recording holds the fused pose too; the limits and every-Nth keep what they say; a folder
# that is not new or empty is refused with one line.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/record"
rm -rf "$out"; mkdir -p "$out"
frames=$(($(wc -l < "$WORK/train/frames.csv") - 1))

# 1. Record the training run without a map (exit 0: nothing is localised, as asked).
"$BIN/harmoloc" --dataset "$WORK/train" --record "$out/rec" --quiet > /dev/null || fail "recording failed"
for f in metadata.toml frames.csv areas.csv encoders.csv; do test -s "$out/rec/$f" || fail "no $f"; done
test ! -e "$out/rec/estimate.tum" || fail "estimate.tum written without a map"
recorded=$(($(wc -l < "$out/rec/frames.csv") - 1))
# Unpaced, the host board waits for the disk: every frame is recorded.
[ "$recorded" -eq "$frames" ] || fail "$recorded of $frames frames recorded"
[ "$(ls "$out/rec/frames" | wc -l)" -eq "$recorded" ] || fail "frames.csv and frames/ disagree"
grep -q 'source = "gpio"' "$out/rec/metadata.toml" || fail "metadata does not name encoders.csv"
echo "ok  recorded $recorded of $frames frames, $(($(wc -l < "$out/rec/encoders.csv") - 1)) encoder samples"

# 2. Train from the recording (with the run's labels, as a user adds them) and from its area log.
cp "$WORK/train/labels.tum" "$out/rec/labels.tum"
"$BIN/harmoloc-train" --dataset "$out/rec" --labels "$out/rec/labels.tum" --out "$out/rec.hmap" --quiet \
  > /dev/null || fail "harmoloc-train refused the recording"
"$BIN/harmoloc-train" --areas "$out/rec/areas.csv" --encoders "$out/rec/encoders.csv" \
  --labels "$out/rec/labels.tum" --out "$out/areas.hmap" --quiet > /dev/null \
  || fail "harmoloc-train refused the recording's area log"
rmse() {  # rmse MAP: fused RMSE (cm) on the test run after the first 3 s
  "$BIN/harmoloc" --dataset "$WORK/test" --map "$1" --trajectory "$out/$2.tum" --quiet > /dev/null || fail "replay with $1"
  "$BIN/harmoloc-report" --truth "$WORK/test/groundtruth.tum" --estimate "$out/$2.tum" --out "$out/$2" \
    --skip-initial 3 > /dev/null
  python3 -c "import json,sys; d=json.load(open(sys.argv[1]))['estimate']; print(d.get('after_convergence', d['all'])['rmse_position_cm'])" \
    "$out/$2/summary.json"
}
base=$(rmse "$WORK/tiny.hmap" base)
from_rec=$(rmse "$out/rec.hmap" from_rec)
from_areas=$(rmse "$out/areas.hmap" from_areas)
echo "test run fused RMSE: map from the original $base cm, from the recording $from_rec cm, from its area log $from_areas cm"
bound=$(python3 -c "import sys; b=float(sys.argv[1]); print(max(b + 1.0, 1.5 * b))" "$base")
less_than "$from_rec" "$bound" "RMSE with the map trained from the recording"
less_than "$from_areas" "$bound" "RMSE with the map trained from the recording's area log"

# 3. The recording replays on the host board as it is, with a map.
"$BIN/harmoloc" --dataset "$out/rec" --map "$out/rec.hmap" --trajectory "$out/rec_replay.tum" --quiet \
  > /dev/null || fail "the host board does not replay the recording"
test -s "$out/rec_replay.tum" || fail "no pose replaying the recording"

# 4. With a map: estimate.tum is the fused pose the run published.
"$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --trajectory "$out/live.tum" \
  --record "$out/with_map" --record-every 4 --stats "$out/with_map.json" --quiet > /dev/null || fail "recording with a map"
cmp -s "$out/live.tum" "$out/with_map/estimate.tum" || fail "estimate.tum differs from the trajectory"
test_frames=$(($(wc -l < "$WORK/test/frames.csv") - 1))
every4=$(($(wc -l < "$out/with_map/frames.csv") - 1))
[ "$every4" -eq $(((test_frames + 3) / 4)) ] \
  || fail "--record-every 4 kept $every4 of $test_frames frames"
[ "$(json_number "$out/with_map.json" recording.frames)" -eq "$every4" ] || fail "the stats' recording.frames"
[ "$(json_number "$out/with_map.json" recording.skipped)" -eq $((test_frames - every4)) ] || fail "the stats' recording.skipped"
echo "ok  with a map: estimate.tum is the run's trajectory; --record-every 4 kept $every4 of $test_frames frames"

# 5. Limits: --record-seconds 2 keeps frames within 2 s of the first, and says why it stopped.
"$BIN/harmoloc" --dataset "$WORK/train" --record "$out/two_s" --record-seconds 2 2> "$out/two_s.err" > /dev/null \
  || fail "recording with a time limit"
span=$(python3 -c "import sys; t=[int(l.split(',')[0]) for l in open(sys.argv[1]).read().split('\n')[1:] if l]; print((t[-1]-t[0])/1e9)" "$out/two_s/frames.csv")
less_than "$span" 2.0 "seconds of frames recorded with --record-seconds 2"
grep -q 'time limit' "$out/two_s.err" || fail "the time limit is not said"
"$BIN/harmoloc" --dataset "$WORK/train" --record "$out/small" --record-max-mb 1 --quiet > /dev/null \
  || fail "recording with a size limit"
bytes=$(du -sb "$out/small/frames" | cut -f1)
[ "$bytes" -le 1100000 ] || fail "--record-max-mb 1 wrote $bytes bytes of frames"

# 5b. The camera's mounting from the config's [camera] goes into the recording's metadata, for the
# trainer's geometry fit (docs/training.md).
printf '[camera]\nheight_m = 0.42\nforward_offset_m = 0.125\n' > "$out/mount.toml"
"$BIN/harmoloc" --dataset "$WORK/train" --config "$out/mount.toml" --record "$out/mounted" \
  --record-seconds 1 --quiet > /dev/null 2>&1 || fail "recording with the camera's mounting"
grep -q '^height_m = 0.42$' "$out/mounted/metadata.toml" || fail "camera.height_m not recorded"
grep -q '^forward_offset_m = 0.125$' "$out/mounted/metadata.toml" \
  || fail "camera.forward_offset_m not recorded"
echo "ok  the config's camera mounting recorded in metadata.toml"

# 6. Refused with one line and exit status 2: a folder that is not empty, a file, no map nor record.
expect_refused() {  # expect_refused PATTERN ARGS...
  local pattern=$1; shift
  set +e; "$BIN/harmoloc" --dataset "$WORK/train" --quiet "$@" > /dev/null 2> "$out/err.txt"; local rc=$?; set -e
  [ "$rc" -eq 2 ] || fail "exit $rc for $*"
  [ "$(wc -l < "$out/err.txt")" -eq 1 ] || fail "not one line for $*: $(cat "$out/err.txt")"
  grep -q -- "$pattern" "$out/err.txt" || fail "'$pattern' not said for $*: $(cat "$out/err.txt")"
}
expect_refused 'not empty' --record "$out/rec"
touch "$out/a_file"
expect_refused 'not a folder' --record "$out/a_file"
expect_refused '--map is required' --trajectory "$out/x.tum"
expect_refused 'record-every' --record "$out/zero" --record-every 0
echo "ok  refused: a folder that is not empty, a file, a run without a map or a recording, --record-every 0"
