#!/usr/bin/env bash
# Automatic colour windows against a random scene's true ones (docs/colours.md): for each seed,
# simulate the scene's training run, propose windows with harmoloc-colours, train a map with each
# set of windows and print the trainer's cross-validated error (cm) of both and their ratio.
# Usage: compare_windows.sh BIN_DIR WORK_DIR SEED...   (not part of ctest: minutes per seed)
set -euo pipefail
bin=$1 work=$2
shift 2
mkdir -p "$work"
cv() {  # the trainer's CV RMSE x and y (cm) -> their root sum of squares
  awk '/^x axis/ { for (i = 1; i <= NF; ++i) if ($i == "RMSE") x = $(i + 1) }
       /^y axis/ { for (i = 1; i <= NF; ++i) if ($i == "RMSE") y = $(i + 1) }
       END { printf "%.3f", sqrt(x * x + y * y) }' "$1"
}
printf 'seed  boards(true/auto)  cv_true_cm  cv_auto_cm  ratio\n'
for seed in "$@"; do
  d=$work/$seed
  [ -f "$d/frames.csv" ] || "$bin/harmoloc-sim" --random "$seed" --out "$d" > "$d.sim.log" 2>&1
  "$bin/harmoloc-colours" --dataset "$d" --config "$d/harmoloc.toml" --out "$d/auto.toml" \
    --quiet 2> "$d.colours.log"
  for w in harmoloc auto; do
    "$bin/harmoloc-train" --dataset "$d" --labels "$d/labels.tum" --config "$d/$w.toml" \
      --out "$d/$w.hmap" > "$d.train-$w.log" 2>&1
  done
  t=$(cv "$d.train-harmoloc.log") a=$(cv "$d.train-auto.log")
  nt=$(grep -c '^\[\[board\]\]' "$d/harmoloc.toml") na=$(grep -c '^\[\[board\]\]' "$d/auto.toml")
  printf '%4s  %7s  %10s  %10s  %5.3f\n' "$seed" "$nt/$na" "$t" "$a" "$(echo "$a / $t" | bc -l)"
done
