#!/usr/bin/env bash
# Fixture: simulates the tiny scenario twice (training run, test run) and a 16-bit-counter run,
# and trains a map on the training run.
source "$(dirname "$0")/lib.sh" "$@"
rm -rf "$WORK/train" "$WORK/test" "$WORK/wrap16"
"$BIN/harmoloc-sim" --scenario tiny --seed 1 --out "$WORK/train" --quiet
"$BIN/harmoloc-sim" --scenario tiny --seed 2 --out "$WORK/test" --quiet
"$BIN/harmoloc-sim" --scenario tiny-wrap16 --seed 3 --out "$WORK/wrap16" --quiet
"$BIN/harmoloc-train" --dataset "$WORK/train" --labels "$WORK/train/labels.tum" --out "$WORK/tiny.hmap"
test -s "$WORK/tiny.hmap" || fail "no map written"
