#!/usr/bin/env bash
# Bad input: a missing or corrupt map, config, frame, encoder log or metadata gives exit status 2
# and exactly one line on stderr, never a crash.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/bad"
rm -rf "$out"; mkdir -p "$out"

make_dataset 40 "$out/good"

cases=0
expect_error() {  # expect_error NAME PATTERN COMMAND...
  local name=$1 pattern=$2; shift 2
  local status=0
  "$@" > "$out/stdout" 2> "$out/stderr" || status=$?
  [ "$status" -eq 2 ] || { cat "$out/stderr"; fail "$name: exit status $status, expected 2"; }
  [ "$(wc -l < "$out/stderr")" -eq 1 ] || { cat "$out/stderr"; fail "$name: expected exactly one line on stderr"; }
  grep -q -- "$pattern" "$out/stderr" || { cat "$out/stderr"; fail "$name: message does not mention '$pattern'"; }
  echo "ok  $name: $(cat "$out/stderr")"
  cases=$((cases + 1))
}
run() { "$BIN/harmoloc" --dataset "$1" --map "$2" --trajectory "$out/t.tum" --quiet "${@:3}"; }

# The good one works.
run "$out/good" "$WORK/tiny.hmap" > /dev/null || fail "the unbroken small dataset failed"

# Maps.
expect_error "missing map" "cannot open" run "$out/good" "$out/nope.hmap"
: > "$out/empty.hmap"
expect_error "empty map" "too short" run "$out/good" "$out/empty.hmap"
head -c 200 "$WORK/tiny.hmap" > "$out/truncated.hmap"
expect_error "truncated map" "map" run "$out/good" "$out/truncated.hmap"
python3 - "$WORK/tiny.hmap" "$out/flipped.hmap" <<'PY'
import sys
d = bytearray(open(sys.argv[1], 'rb').read()); d[len(d) // 2] ^= 1; open(sys.argv[2], 'wb').write(d)
PY
expect_error "map with a flipped bit" "checksum" run "$out/good" "$out/flipped.hmap"
printf 'this is not a map at all, just text that is long enough\n' > "$out/text.hmap"
expect_error "text instead of a map" "magic" run "$out/good" "$out/text.hmap"

# Configs.
printf '[cycle]\nrate_hz = 30\nbudget_sm = 15\n' > "$out/typo.toml"
expect_error "config with an unknown key" "unknown key 'cycle.budget_sm'" run "$out/good" "$WORK/tiny.hmap" --config "$out/typo.toml"
printf '[filter]\nparticles = 100000\n' > "$out/range.toml"
expect_error "config value out of range" "filter.particles" run "$out/good" "$WORK/tiny.hmap" --config "$out/range.toml"
printf '[cycle\nrate_hz = 30\n' > "$out/syntax.toml"
expect_error "config that is not TOML" "line" run "$out/good" "$WORK/tiny.hmap" --config "$out/syntax.toml"
printf '[realtime]\npriority = 120\n' > "$out/rt.toml"
expect_error "real-time priority out of range" "realtime.priority" run "$out/good" "$WORK/tiny.hmap" --config "$out/rt.toml"
expect_error "missing config" "nope.toml: cannot open" run "$out/good" "$WORK/tiny.hmap" --config "$out/nope.toml"
printf '[[board]]\nname = "red"\nhue_deg = [0, 20]\n' > "$out/other_thresholds.toml"
expect_error "map trained with other thresholds" "retrain" run "$out/good" "$WORK/tiny.hmap" --config "$out/other_thresholds.toml"

# Frames.
make_dataset 40 "$out/truncated_frame"
f=$(sed -n 10p "$out/truncated_frame/frames.csv" | cut -d, -f2)
head -c 1000 "$WORK/test/$f" > "$out/truncated_frame/$f"
expect_error "truncated frame" "truncated" run "$out/truncated_frame" "$WORK/tiny.hmap"
make_dataset 40 "$out/garbage_frame"
f=$(sed -n 5p "$out/garbage_frame/frames.csv" | cut -d, -f2)
head -c "$(stat -c %s "$WORK/test/$f")" /dev/urandom > "$out/garbage_frame/$f"
expect_error "garbage frame" "PPM" run "$out/garbage_frame" "$WORK/tiny.hmap"
make_dataset 40 "$out/missing_frame"
rm "$out/missing_frame/frames/000003.ppm"
expect_error "missing frame" "000003.ppm" run "$out/missing_frame" "$WORK/tiny.hmap"
make_dataset 40 "$out/bad_index"
sed -i '7s/.*/12x34,frames\/000005.ppm/' "$out/bad_index/frames.csv"
expect_error "bad frame index" "frames.csv:7" run "$out/bad_index" "$WORK/tiny.hmap"

# Encoder logs.
make_dataset 40 "$out/bad_log"
sed -i '20s/.*/(1767225600.190000) can0 181#00112233445566778899/' "$out/bad_log/encoders.log"
expect_error "encoder log with an over-long frame" "encoders.log:20" run "$out/bad_log" "$WORK/tiny.hmap"
make_dataset 40 "$out/no_log"
rm "$out/no_log/encoders.log"
expect_error "missing encoder log" "encoders.log" run "$out/no_log" "$WORK/tiny.hmap"

# Metadata and datasets.
expect_error "missing dataset" "metadata.toml" run "$out/does_not_exist" "$WORK/tiny.hmap"
make_dataset 40 "$out/bad_meta"
sed -i 's/pixel_format = "rgb24"/pixel_format = "nv12"/' "$out/bad_meta/metadata.toml"
expect_error "unknown pixel format" "pixel_format" run "$out/bad_meta" "$WORK/tiny.hmap"
make_dataset 40 "$out/other_size"
sed -i 's/width_px = 160/width_px = 320/' "$out/other_size/metadata.toml"
expect_error "map for another frame size" "trained on 160x120" run "$out/other_size" "$WORK/tiny.hmap"

# Inputs of the adversarial probe (issue 16): each used to run (exit 0), crash, block or eat
# memory. Every file read must be a regular file in its place, size-capped before it is read.
expect_error "config that is a folder" "not a regular file (a directory)" run "$out/good" "$WORK/tiny.hmap" --config "$out"
expect_error "config that is /dev/zero" "not a regular file (a character device)" run "$out/good" "$WORK/tiny.hmap" --config /dev/zero
rm -f "$out/config.fifo"; mkfifo "$out/config.fifo"
expect_error "config that is a FIFO" "not a regular file (a FIFO)" timeout 20 "$BIN/harmoloc" --dataset "$out/good" --map "$WORK/tiny.hmap" --config "$out/config.fifo" --quiet
python3 -c "print('a.' * 50000 + 'a = 1')" > "$out/deep.toml"
expect_error "config of 50,000 dotted keys" "nested 50001 deep" run "$out/good" "$WORK/tiny.hmap" --config "$out/deep.toml"
make_dataset 40 "$out/deep_meta"
python3 -c "print('a.' * 50000 + 'a = 1')" >> "$out/deep_meta/metadata.toml"
expect_error "metadata of 50,000 dotted keys" "metadata.toml: line [0-9]*: nested 50002 deep" run "$out/deep_meta" "$WORK/tiny.hmap"
make_dataset 40 "$out/zero_log"
sed -i 's#^log = .*#log = "/dev/zero"#' "$out/zero_log/metadata.toml"
expect_error "encoder log /dev/zero" "encoders.log '/dev/zero' must be a path relative" run "$out/zero_log" "$WORK/tiny.hmap"
make_dataset 40 "$out/outside_index"
sed -i 's#^frames_index = .*#frames_index = "../good/frames.csv"#' "$out/outside_index/metadata.toml"
expect_error "frame index outside the dataset" "camera.frames_index '../good/frames.csv' must stay inside" run "$out/outside_index" "$WORK/tiny.hmap"
make_dataset 40 "$out/fifo_log"
rm "$out/fifo_log/encoders.log"; mkfifo "$out/fifo_log/encoders.log"
expect_error "encoder log that is a FIFO" "encoders.log: not a regular file (a FIFO)" timeout 20 "$BIN/harmoloc" --dataset "$out/fifo_log" --map "$WORK/tiny.hmap" --quiet
make_dataset 40 "$out/empty_log"
: > "$out/empty_log/encoders.log"
expect_error "empty encoder log" "encoders.log: no CAN frames" run "$out/empty_log" "$WORK/tiny.hmap"
make_dataset 40 "$out/folder_log"
rm "$out/folder_log/encoders.log"; mkdir "$out/folder_log/encoders.log"
expect_error "encoder log that is a folder" "encoders.log: not a regular file (a directory)" run "$out/folder_log" "$WORK/tiny.hmap"
make_dataset 40 "$out/foreign_log"
sed -i 's/ 181#/ 182#/' "$out/foreign_log/encoders.log"
expect_error "encoder log without encoder frames" "is an encoder frame (ID 0x181" run "$out/foreign_log" "$WORK/tiny.hmap"
redate() {  # redate LOG LINE SECONDS: moves one candump line's timestamp by SECONDS
  python3 - "$@" <<'PY'
import sys
path, n, shift = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
lines = open(path).read().splitlines()
s = lines[n - 1]
lines[n - 1] = '(%.6f)' % (float(s[1:s.index(')')]) + shift) + s[s.index(')') + 1:]
open(path, 'w').write('\n'.join(lines) + '\n')
PY
}
make_dataset 40 "$out/past_line"
redate "$out/past_line/encoders.log" 100 -5
expect_error "encoder log line dated in the past" "encoders.log:100: timestamp .* is before line 99's" run "$out/past_line" "$WORK/tiny.hmap"
make_dataset 40 "$out/future_line"
redate "$out/future_line/encoders.log" 100 100000
expect_error "encoder log line dated in the future" "encoders.log:101: timestamp .* is before line 100's" run "$out/future_line" "$WORK/tiny.hmap"
# A map file far larger than any map (300 MB, sparse): refused from its size, unread (it used to
# take 529 MB of memory).
python3 - "$WORK/tiny.hmap" "$out/huge.hmap" <<'PY'
import sys
d = open(sys.argv[1], 'rb').read()
with open(sys.argv[2], 'wb') as f:
    f.write(d); f.truncate(300 * 1000 * 1000)
PY
expect_error "map of 300 MB" "300000000 bytes, more than the" run "$out/good" "$out/huge.hmap"
peak_kb=$(python3 - "$BIN/harmoloc" "$out/good" "$out/huge.hmap" <<'PY'
import resource, subprocess, sys
subprocess.run([sys.argv[1], '--dataset', sys.argv[2], '--map', sys.argv[3], '--quiet'],
               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
PY
)
[ "$peak_kb" -lt 100000 ] || fail "the 300 MB map took $peak_kb kB of memory"
echo "ok  the 300 MB map was refused with a peak of $peak_kb kB"
# A map whose training target is at 1e30 m (a label at 1e30 gave one; the firmware published
# 3.7e28 m as a nominal pose).
python3 - "$WORK/tiny.hmap" "$out/far.hmap" <<'PY'
import struct, sys, zlib
d = bytearray(open(sys.argv[1], 'rb').read())
boards = struct.unpack_from('<I', d, 20)[0]
off = 24 + 12 * boards
n, f = struct.unpack_from('<II', d, off)
off += 8 + f + 7 * 4 + 4 * f  # header, the feature boards, 7 parameters, the feature weights
struct.pack_into('<f', d, off + 4 * f, 1e30)  # sample 0's x
struct.pack_into('<I', d, len(d) - 4, zlib.crc32(bytes(d[:-4])))
open(sys.argv[2], 'wb').write(d)
PY
expect_error "map with a training target at 1e30 m" "sample coordinate farther than 10 km" run "$out/good" "$out/far.hmap"

# The host tools.
expect_error "sim: unknown scenario" "unknown scenario" "$BIN/harmoloc-sim" --scenario nowhere --out "$out/x" --quiet
printf 'base = "tiny"\n[camera]\nwidht_px = 320\n' > "$out/typo_scenario.toml"
expect_error "sim: scenario with a typo" "unknown key 'camera.widht_px'" "$BIN/harmoloc-sim" --scenario "$out/typo_scenario.toml" --out "$out/x" --quiet
printf '1 2 3\n' > "$out/bad_labels.tum"
expect_error "train: malformed labels" "bad_labels.tum:1" "$BIN/harmoloc-train" --dataset "$out/good" --labels "$out/bad_labels.tum" --out "$out/x.hmap"
printf '5.0 1 1 0 0 0 0 1\n' > "$out/far_labels.tum"
expect_error "train: labels that match no frame" "outside the run" "$BIN/harmoloc-train" --dataset "$out/good" --labels "$out/far_labels.tum" --out "$out/x.hmap"
expect_error "sweep: seed 0 (the default scene's)" "random scene seeds are 1 and up" "$BIN/harmoloc-sweep" --seeds 3,0 --out "$out/sweep" --quiet
expect_error "report: missing truth" "harmoloc-report" "$BIN/harmoloc-report" --truth "$out/nope.tum" --estimate "$out/t.tum" --out "$out/r"
expect_error "report: no estimate" "--estimate is required" "$BIN/harmoloc-report" --truth "$out/t.tum" --out "$out/r"
expect_error "report: one run to compare" "at least two runs" "$BIN/harmoloc-report" --truth "$out/t.tum" --compare "a=$out/t.tum" --out "$out/r"
expect_error "report: compare a missing run" "nope.tum: no such file" "$BIN/harmoloc-report" --truth "$out/t.tum" --compare "a=$out/t.tum" "b=$out/nope.tum" --out "$out/r"

echo "OK: $cases bad inputs rejected with one line and exit status 2"
