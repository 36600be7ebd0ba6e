#!/usr/bin/env bash
# The scenario tests' map: desk-shuttle's training run (seed 1) simulated and trained, as a user
# would (harmoloc-sim, harmoloc-train); the frames are removed afterwards (200 MB).
#   setup.sh BIN_DIR WORK_DIR
set -euo pipefail
bin=$1 work=$2
mkdir -p "$work"
if [ -f "$work/desk-shuttle.hmap" ] && [ "$work/desk-shuttle.hmap" -nt "$bin/harmoloc-train" ] \
   && [ "$work/desk-shuttle.hmap" -nt "$bin/harmoloc-sim" ]; then
  echo "map up to date: $work/desk-shuttle.hmap"
  exit 0
fi
rm -rf "$work/train"
"$bin/harmoloc-sim" --scenario desk-shuttle --seed 1 --out "$work/train" > /dev/null
"$bin/harmoloc-train" --dataset "$work/train" --labels "$work/train/labels.tum" \
  --out "$work/desk-shuttle.hmap.tmp" --quiet
mv "$work/desk-shuttle.hmap.tmp" "$work/desk-shuttle.hmap"
rm -rf "$work/train"
