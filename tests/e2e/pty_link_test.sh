#!/usr/bin/env bash
# The link on a serial device: a pty, the firmware paced at the recording's rate (--realtime),
# the other end read by a separate process and decoded by node-mavlink.
source "$(dirname "$0")/lib.sh" "$1" "$2"
DECODER_DIR=$3
out="$WORK/pty"
rm -rf "$out"; mkdir -p "$out"
make_dataset 60 "$out/cut"
python3 - "$BIN/harmoloc" "$out" <<'PY'
import os, pty, select, subprocess, sys, time
harmoloc, out = sys.argv[1], sys.argv[2]
master, slave = pty.openpty()
start = time.monotonic()
p = subprocess.Popen([harmoloc, "--dataset", f"{out}/cut", "--map", f"{out}/../tiny.hmap", "--link", os.ttyname(slave),
                      "--trajectory", f"{out}/est.tum", "--stats", f"{out}/stats.json", "--realtime", "--quiet"],
                     stdout=subprocess.DEVNULL)
data = bytearray()
while True:
    ready, _, _ = select.select([master], [], [], 0.2)
    if ready:
        data += os.read(master, 65536)
    elif p.poll() is not None:
        break
    if time.monotonic() - start > 30:
        p.kill()
        sys.exit("FAIL: harmoloc did not finish within 30 s")
wall = time.monotonic() - start
open(f"{out}/link.bin", "wb").write(data)
print(f"harmoloc exit {p.returncode}, {len(data)} bytes through the pty in {wall:.1f} s")
if p.returncode != 0:
    sys.exit("FAIL: harmoloc failed")
if wall < 1.5:
    sys.exit(f"FAIL: --realtime run of 2 s of data took only {wall:.1f} s")
PY
node "$DECODER_DIR/decode_link.js" "$out/link.bin" "$out/est.tum"
[ "$(json_number "$out/stats.json" link.frames_dropped)" -eq 0 ] || fail "frames dropped on an idle pty"
python3 -c "import json,sys; w=json.load(open(sys.argv[1]))['wakeup_latency']; assert w['count'] >= 55, w; print('wake-up latency', w)" "$out/stats.json" || fail "no wake-up latency in a paced run's stats"
"$BIN/harmoloc-budget" "$out/stats.json" | grep -q "^wake-up" || fail "harmoloc-budget does not show the wake-up latency"
"$BIN/harmoloc-budget" "$out/stats.json" | grep -q "^pacing     camera, 0 skipped ticks" || fail "harmoloc-budget does not show the pacing"
