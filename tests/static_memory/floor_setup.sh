#!/usr/bin/env bash
# Fixture: a floor map for the static-memory test. Random scene 5 (320 x 240): its coverage run
# (lanes over the floor at several headings) trained into a floor map with bearings and
# visibility (a floor map's default), and a roam of the floor that no lane drove, with two
# carries of the robot to elsewhere on the floor.
source "$(dirname "$0")/../e2e/lib.sh" "$@"
rm -rf "$WORK/floor-coverage" "$WORK/floor-roam"
"$BIN/harmoloc-sim" --random 5 --variant coverage --out "$WORK/floor-coverage" --quiet
"$BIN/harmoloc-sim" --random 5 --variant roam --roam-seed 1 --waypoints 6 --kidnaps 2 \
  --lighting 101 --run-seed 101 --out "$WORK/floor-roam" --quiet
"$BIN/harmoloc-train" --dataset "$WORK/floor-coverage" --labels "$WORK/floor-coverage/labels.tum" \
  --config "$WORK/floor-coverage/harmoloc.toml" --out "$WORK/floor.hmap" > "$WORK/floor-train.txt"
grep -q "a floor map" "$WORK/floor-train.txt" || fail "the coverage run did not train a floor map"
grep -q "^visibility    each board" "$WORK/floor-train.txt" ||
  fail "the floor map holds no visibility (a floor map's default)"
test -s "$WORK/floor.hmap" || fail "no floor map written"
# The test reads the coverage run's config and the roam, not the coverage frames (2 GB): freed
# here so that a CI run, which builds the suite several times, does not fill the disk.
rm -rf "$WORK/floor-coverage/frames"
