#!/usr/bin/env bash
# GPIO encoder recordings (docs/dataset-format.md, encoders.csv): the firmware records the counts
# it reads with --record-encoders; a copy of the dataset whose metadata says
# [encoders] source = "gpio" replays that recording instead of the CAN log and must give the same
# trajectory byte for byte (the cycle sees the same counts at the same times). One changed count
# must change it (the check is not vacuous), and a malformed recording stops start-up with
# FILE:LINE and exit status 2.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/gpio"
rm -rf "$out"; mkdir -p "$out"

run() { "$BIN/harmoloc" --dataset "$1" --map "$WORK/tiny.hmap" --trajectory "$2" --quiet "${@:3}"; }

# 1. Record while replaying the CAN log (also with 16-bit counters: the wrap16 run).
run "$WORK/test" "$out/can.tum" --record-encoders "$out/encoders.csv" > /dev/null
head -1 "$out/encoders.csv" | grep -qx 'timestamp_ns,left_ticks,right_ticks' || fail "no header"
lines=$(($(wc -l < "$out/encoders.csv") - 1))
frames=$(($(wc -l < "$WORK/test/frames.csv") - 1))
[ "$lines" -gt $((frames / 2)) ] || fail "only $lines samples recorded for $frames frames"
echo "recorded $lines samples over $frames frames"

# 2. The same dataset with the GPIO recording as its encoder source.
make_gpio_copy() {  # make_gpio_copy SRC DST CSV
  rm -rf "$2"; mkdir -p "$2"
  ln -s "$(cd "$1" && pwd)/frames" "$2/frames"
  cp "$1/frames.csv" "$2/"
  cp "$3" "$2/encoders.csv"
  python3 - "$1/metadata.toml" "$2/metadata.toml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
text = text.replace('[encoders]\n', '[encoders]\nsource = "gpio"\n', 1)
text = re.sub(r'^log = .*$', 'log = "encoders.csv"', text, flags=re.M)
open(sys.argv[2], 'w').write(text)
PY
}
make_gpio_copy "$WORK/test" "$out/gpio" "$out/encoders.csv"
run "$out/gpio" "$out/gpio.tum" --stats "$out/gpio.json" > /dev/null
cmp -s "$out/can.tum" "$out/gpio.tum" || fail "the GPIO recording's replay differs from the CAN log's"
samples=$(json_number "$out/gpio.json" encoders.samples)
[ "$samples" -eq "$lines" ] || fail "stats count $samples samples, the recording has $lines"
echo "ok  replaying the GPIO recording gives the CAN log's trajectory byte for byte"

# The 16-bit run: the recording carries counts that wrap at 2^16.
run "$WORK/wrap16" "$out/can16.tum" --record-encoders "$out/encoders16.csv" > /dev/null
make_gpio_copy "$WORK/wrap16" "$out/gpio16" "$out/encoders16.csv"
grep -q 'counter_bits = 16' "$out/gpio16/metadata.toml" || fail "wrap16 metadata lost its width"
run "$out/gpio16" "$out/gpio16.tum" > /dev/null
cmp -s "$out/can16.tum" "$out/gpio16.tum" || fail "16-bit GPIO replay differs"
python3 - "$out/encoders16.csv" <<'PY' || fail "the 16-bit recording never wraps"
import sys
rows = [list(map(int, l.split(','))) for l in open(sys.argv[1]).read().split('\n')[1:] if l]
assert all(0 <= v < 65536 for r in rows for v in r[1:]), "a count beyond 16 bits"
assert any(b[1] < a[1] - 30000 or b[2] < a[2] - 30000 for a, b in zip(rows, rows[1:]))
PY
echo "ok  16-bit counts recorded and replayed across the wrap"

# 3. Negative control: one count changed mid-run changes the trajectory.
python3 - "$out/encoders.csv" "$out/tampered.csv" <<'PY'
import sys
lines = open(sys.argv[1]).read().split('\n')
k = len(lines) // 2
t, l, r = lines[k].split(',')
for j in range(k, len(lines)):
    if lines[j]:
        t2, l2, r2 = lines[j].split(',')
        lines[j] = f"{t2},{(int(l2) + 400) % 2**32},{r2}"
open(sys.argv[2], 'w').write('\n'.join(lines))
PY
make_gpio_copy "$WORK/test" "$out/tampered" "$out/tampered.csv"
run "$out/tampered" "$out/tampered.tum" > /dev/null
if cmp -s "$out/can.tum" "$out/tampered.tum"; then fail "a changed recording gave the same trajectory"; fi
echo "ok  a changed count changes the trajectory"

# 4. Malformed recordings: exit 2, one line naming FILE:LINE.
expect_error() {  # expect_error NAME PATTERN DATASET
  local status=0
  run "$3" "$out/x.tum" > "$out/stdout" 2> "$out/stderr" || status=$?
  [ "$status" -eq 2 ] || { cat "$out/stderr"; fail "$1: exit status $status, expected 2"; }
  [ "$(wc -l < "$out/stderr")" -eq 1 ] || { cat "$out/stderr"; fail "$1: expected one line"; }
  grep -q -- "$2" "$out/stderr" || { cat "$out/stderr"; fail "$1: no '$2' in the message"; }
  echo "ok  $1: $(cat "$out/stderr")"
}
make_gpio_copy "$WORK/test" "$out/bad" "$out/encoders.csv"
sed -i '7s/.*/1767225600100000000,12,x/' "$out/bad/encoders.csv"
expect_error "a count that is not a number" "encoders.csv:7: " "$out/bad"
make_gpio_copy "$WORK/test" "$out/bad" "$out/encoders.csv"
sed -i '9{h;d};10G' "$out/bad/encoders.csv"  # lines 9 and 10 swapped
expect_error "timestamps out of order" "encoders.csv:10: .*not after" "$out/bad"
make_gpio_copy "$WORK/test" "$out/bad" "$out/encoders.csv"
sed -i 's/counter_bits = 32/counter_bits = 8/' "$out/bad/metadata.toml"
expect_error "counts wider than the metadata's counter_bits" "encoders.csv:[0-9]*: .*counter width" "$out/bad"
make_gpio_copy "$WORK/test" "$out/bad" "$out/encoders.csv"
sed -i '1s/.*/t,l,r/' "$out/bad/encoders.csv"
expect_error "a foreign header" "encoders.csv:1: " "$out/bad"
rm "$out/bad/encoders.csv"
expect_error "a missing recording" "encoders.csv: cannot open" "$out/bad"
echo "OK: GPIO encoder recordings"
