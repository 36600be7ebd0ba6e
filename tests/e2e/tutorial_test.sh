#!/usr/bin/env bash
# docs/training.md's workflow, step by step with its own commands, on a robot nobody configured:
# a random scene of the simulator stands in for the room, the camera and the encoders (the host
# board replays it as the Linux board would read the devices). The robot's config knows its
# geometry and encoder frames but no board. Then, as the tutorial says:
#   2. record a run before any map exists     harmoloc --config ... --record run
#   1. choose the colours from that recording harmoloc-colours --dataset run --config ... --out
#   3. label a few poses                      (the simulator's labels.tum: 64 over the run)
#   4. train                                  harmoloc-train --dataset run --labels ... --out map
#   5. run with the map                       harmoloc --config ... --map map.hmap
# on a second run of the same route (other noise and lighting). The fused pose must be within a
# few centimetres of the truth, and the colour tool must have found the scene's boards.
source "$(dirname "$0")/lib.sh" "$@"
BIN=$(cd "$BIN" && pwd)
out="$WORK/tutorial"
rm -rf "$out"
mkdir -p "$out"
cd "$out"
seed=18  # 320x240, 3 boards, a 4.3 m route in 53 s: quick to render
# The room, driven twice: the training run and, in other light, the run to localize on.
"$BIN/harmoloc-sim" --random $seed --out room --quiet
"$BIN/harmoloc-sim" --random $seed --run-seed 1$seed --lighting 7 --out room-later --quiet
# The robot's own config: everything the scene's config says but its boards.
sed '/^\[\[board\]\]/,$d' room/harmoloc.toml > robot.toml
grep -q '^\[odometry\]' robot.toml || fail "no [odometry] in the robot's config"
! grep -q '^\[\[board\]\]' robot.toml || fail "the robot's config still names boards"

# Step 2: record (the host board reads the room's frames and encoder frames as the devices).
"$BIN/harmoloc" --dataset room --config robot.toml --record run --quiet > record.txt ||
  fail "recording failed: $(tail -2 record.txt)"
for f in metadata.toml frames.csv areas.csv encoders.csv; do
  test -s "run/$f" || fail "the recording has no $f"
done
# Step 1: the colour windows from the recording.
"$BIN/harmoloc-colours" --dataset run --config robot.toml --out harmoloc.toml > colours.txt 2>&1 ||
  fail "harmoloc-colours failed: $(tail -3 colours.txt)"
found=$(grep -c '^\[\[board\]\]' harmoloc.toml)
truth=$(grep -c '^\[\[board\]\]' room/harmoloc.toml)
[ "$found" -eq "$truth" ] || fail "harmoloc-colours proposed $found boards, the room has $truth"
test -s colours-preview/index.html || fail "no colours preview beside harmoloc.toml"
grep -q '^\[odometry\]' harmoloc.toml || fail "harmoloc-colours dropped the robot's [odometry]"
# Steps 3 and 4: the labels, and the map trained from the recording with the chosen windows.
cp room/labels.tum labels.tum
"$BIN/harmoloc-train" --dataset run --labels labels.tum --config harmoloc.toml --out map.hmap \
  > train.txt || fail "training failed: $(tail -3 train.txt)"
# Step 5: the firmware with the map, on the later run.
"$BIN/harmoloc" --dataset room-later --config harmoloc.toml --map map.hmap \
  --trajectory pose.tum --stats stats.json --quiet > run.txt || fail "the run with the map failed"
"$BIN/harmoloc-report" --truth room-later/groundtruth.tum --estimate pose.tum --stats stats.json \
  --skip-initial 3 --out report > /dev/null
rmse=$(json_number report/summary.json estimate.all.rmse_position_cm)
echo "tutorial on random scene $seed: $found boards found, fused RMSE $rmse cm on the later run"
less_than "$rmse" 3 "fused RMSE (cm) with the map the tutorial made"
rm -rf room room-later run  # about 1 GB of frames; the rest stays to look at
