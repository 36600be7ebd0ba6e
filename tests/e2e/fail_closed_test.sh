#!/usr/bin/env bash
# What the adversarial probe of issue 16 found at run time, each now closed (docs/reliability.md,
# "Adversarial probes"): a signal or a vanished link reader loses no output, a failed output says
# so when it fails and names its file, a hole in the recording is noticed, a run that never
# localises does not look like success, and every tool's command line speaks one line and exit 2.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/fail_closed"
rm -rf "$out"; mkdir -p "$out"
run() { "$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" "$@"; }
frames=$(($(wc -l < "$WORK/test/frames.csv") - 1))

# --- Signals: SIGTERM, SIGINT and SIGHUP stop the run at the next cycle with every output written
# (before: exit 143/129, the trajectory and the stats left empty; SIGINT too, outside a shell's
# background job, which ignores it). Job control on, so that a background job may get SIGINT.
set -m
for sig in TERM INT HUP; do
  rm -f "$out/sig.tum" "$out/sig.json"
  "$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --realtime \
    --trajectory "$out/sig.tum" --stats "$out/sig.json" --quiet > "$out/sig.out" 2>&1 &
  pid=$!
  sleep 2
  kill -s "$sig" "$pid"
  status=0; wait "$pid" || status=$?
  [ "$status" -eq 0 ] || { cat "$out/sig.out"; fail "SIG$sig: exit status $status, expected 0"; }
  lines=$(wc -l < "$out/sig.tum")
  [ "$lines" -ge 30 ] && [ "$lines" -lt "$frames" ] || fail "SIG$sig: $lines poses in the trajectory"
  [ "$(json_number "$out/sig.json" ended)" = "SIG$sig" ] || fail "SIG$sig: the stats do not say so"
  [ "$(json_number "$out/sig.json" cycles)" -ge "$lines" ] || fail "SIG$sig: stats cycles"
  echo "ok  SIG$sig after 2 s: exit 0, $lines poses and the stats written"
done
set +m

# --- The link's reader goes away (a FIFO): SIGPIPE is ignored, the writes fail and are counted,
# the run completes (before: killed by SIGPIPE, exit 141, trajectory empty).
rm -f "$out/link.fifo"; mkfifo "$out/link.fifo"
head -c 1000 "$out/link.fifo" > /dev/null &
reader=$!
status=0
run --realtime --link "$out/link.fifo" --trajectory "$out/pipe.tum" --stats "$out/pipe.json" --quiet > /dev/null || status=$?
wait "$reader" || true
[ "$status" -eq 0 ] || fail "broken link: exit status $status, expected 0"
[ "$(wc -l < "$out/pipe.tum")" -eq "$frames" ] || fail "broken link: the trajectory is not whole"
errors=$(json_number "$out/pipe.json" link.errors)
[ "$errors" -gt 0 ] || fail "broken link: no link error counted"
echo "ok  link reader gone after 1000 bytes: run completed, $errors link errors counted"

# --- A failed output (a full disk: /dev/full behind a name of our own) is reported naming that
# file, while the run goes on; the other outputs and the stats are still written; exit 1 (before:
# "writing the trajectory failed" for the fixes file, exit 2, no stats).
ln -sf /dev/full "$out/fixes.tum"
status=0
run --loop 4 --fixes "$out/fixes.tum" --trajectory "$out/full.tum" --stats "$out/full.json" > /dev/null 2> "$out/full.err" || status=$?
[ "$status" -eq 1 ] || { cat "$out/full.err"; fail "/dev/full: exit status $status, expected 1"; }
grep -q "harmoloc: $out/fixes.tum: write failed (No space left on device)" "$out/full.err" || { cat "$out/full.err"; fail "/dev/full: the failed file is not named"; }
# Said when it failed (a 64 KiB buffer into the run), before the run's last progress line.
failed_at=$(grep -n "fixes.tum: write failed" "$out/full.err" | head -1 | cut -d: -f1)
last_cycle=$(tr '\r' '\n' < "$out/full.err" | grep -n "cycle $((4 * frames))/$((4 * frames))" | head -1 | cut -d: -f1)
[ -n "$last_cycle" ] && [ "$(tr '\r' '\n' < "$out/full.err" | grep -n 'fixes.tum: write failed' | head -1 | cut -d: -f1)" -lt "$last_cycle" ] || { cat "$out/full.err"; fail "/dev/full: not reported while the run went on"; }
[ "$failed_at" -ge 1 ] || fail "/dev/full: not reported"
[ "$(wc -l < "$out/full.tum")" -eq $((4 * frames)) ] || fail "/dev/full: the trajectory was not written whole"
[ "$(json_number "$out/full.json" outputs_failed)" -eq 1 ] || fail "/dev/full: the stats do not count it"
[ "$(json_number "$out/full.json" cycles)" -eq $((4 * frames)) ] || fail "/dev/full: stats cycles"
echo "ok  fixes on a full disk: '$(grep 'fixes.tum' "$out/full.err" | head -1)', exit 1, the rest written"
ln -sf /dev/full "$out/stats.json"
status=0
run --trajectory "$out/t.tum" --stats "$out/stats.json" --quiet > /dev/null 2> "$out/stats.err" || status=$?
[ "$status" -eq 1 ] || fail "stats on /dev/full: exit status $status, expected 1"
grep -q "$out/stats.json: write failed" "$out/stats.err" || { cat "$out/stats.err"; fail "stats on /dev/full: not named"; }
echo "ok  stats on a full disk: exit 1, named"

# --- A hole of 5.6 s in the recording (168 frames missing from frames.csv): the cycle runs on at
# 30 Hz on odometry, the health says so (before: no cycles, health nominal, the link silent).
mkdir -p "$out/hole"
cp "$WORK/test/metadata.toml" "$WORK/test/encoders.log" "$out/hole/"
ln -sfn "$WORK/test/frames" "$out/hole/frames"
awk 'NR <= 101 || NR > 269' "$WORK/test/frames.csv" > "$out/hole/frames.csv"
"$BIN/harmoloc" --dataset "$out/hole" --map "$WORK/tiny.hmap" --stats "$out/hole.json" --link "$out/hole.link" --quiet > /dev/null
[ "$(json_number "$out/hole.json" cycles)" -eq "$frames" ] || fail "hole: $(json_number "$out/hole.json" cycles) cycles, expected $frames"
[ "$(json_number "$out/hole.json" camera.no_frame_cycles)" -eq 168 ] || fail "hole: no_frame_cycles"
odo=$(json_number "$out/hole.json" health_cycles.odometry_only)
[ "$odo" -ge 155 ] || fail "hole: only $odo cycles odometry-only"
grep -q "odometry only (no camera fix)" "$out/hole.link" || fail "hole: no STATUSTEXT on the link"
echo "ok  5.6 s hole in frames.csv: $frames cycles, 168 without a frame, $odo odometry-only, STATUSTEXT sent"

# --- A run that never localises (every frame black): the summary counts the cycles without a
# pose, exit 3, and harmoloc-budget --check does not say "fits" (before: exit 0, "fits").
mkdir -p "$out/black/frames"
cp "$WORK/test/metadata.toml" "$WORK/test/encoders.log" "$WORK/test/frames.csv" "$out/black/"
python3 - "$WORK/test" "$out/black" <<'PY'
import sys
src, dst = sys.argv[1:]
for line in open(src + '/frames.csv').read().splitlines()[1:]:
    name = line.split(',')[1]
    data = open(src + '/' + name, 'rb').read()
    header = b'P6\n160 120\n255\n'
    open(dst + '/' + name, 'wb').write(header + bytes(len(data) - len(header)))
PY
status=0
"$BIN/harmoloc" --dataset "$out/black" --map "$WORK/tiny.hmap" --stats "$out/black.json" --quiet > "$out/black.out" 2> "$out/black.err" || status=$?
[ "$status" -eq 3 ] || { cat "$out/black.out" "$out/black.err"; fail "never localised: exit status $status, expected 3"; }
grep -q "health not initialised $frames / nominal 0" "$out/black.out" || { cat "$out/black.out"; fail "never localised: the summary hides it"; }
[ "$(wc -l < "$out/black.err")" -eq 1 ] || { cat "$out/black.err"; fail "never localised: expected one line on stderr"; }
status=0
"$BIN/harmoloc-budget" --check "$out/black.json" > "$out/budget.out" || status=$?
[ "$status" -eq 1 ] || { cat "$out/budget.out"; fail "never localised: harmoloc-budget --check exit $status"; }
grep -q "NO POSE" "$out/budget.out" && ! grep -q "fits" "$out/budget.out" || { cat "$out/budget.out"; fail "never localised: harmoloc-budget says it fits"; }
echo "ok  never localised: exit 3, '$(cat "$out/black.err")', budget --check exit 1"

# --- Every tool: --version; a usage error is one line "TOOL: reason", exit 2 (before: exit
# 106/109/114, two lines without the tool's name; --seed -1 read as 18446744073709551615).
cli_error() {  # cli_error TOOL PATTERN ARGS...
  local tool=$1 pattern=$2 status=0; shift 2
  "$BIN/$tool" "$@" > /dev/null 2> "$out/cli.err" || status=$?
  [ "$status" -eq 2 ] || { cat "$out/cli.err"; fail "$tool $*: exit status $status, expected 2"; }
  [ "$(wc -l < "$out/cli.err")" -eq 1 ] || { cat "$out/cli.err"; fail "$tool $*: not one line"; }
  grep -q "^$tool: .*$pattern" "$out/cli.err" || { cat "$out/cli.err"; fail "$tool $*: '$pattern' missing"; }
}
version=$(sed -n 's/^project(harmoloc VERSION \([0-9.]*\).*/\1/p' "$(dirname "$0")/../../CMakeLists.txt")
for tool in harmoloc harmoloc-sim harmoloc-train harmoloc-budget harmoloc-report harmoloc-accuracy harmoloc-scenarios; do
  [ "$("$BIN/$tool" --version)" = "$tool $version" ] || fail "$tool --version"
  cli_error "$tool" "" --no-such-option  # (or the first required option it misses)
  "$BIN/$tool" --help > /dev/null || fail "$tool --help"
done
cli_error harmoloc "--dataset is required" --map "$WORK/tiny.hmap"
cli_error harmoloc "--loop" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --loop -1
cli_error harmoloc-sim "--seed: must not be negative: -1" --seed -1 --out "$out/sim"
cli_error harmoloc-sim "--seed" --seed x --out "$out/sim"
cli_error harmoloc-accuracy "must not be negative" --train-seed -3
cli_error harmoloc-train "--labels is required" --dataset "$WORK/train" --out "$out/x.hmap"
echo "ok  7 tools: --version, --help, one-line usage errors with exit 2, negative seeds refused"

echo "OK: signals, broken link, failed outputs, a hole in the recording, a run without a pose, command lines"
