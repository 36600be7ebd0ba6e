#!/usr/bin/env bash
# harmoloc-monitor end to end. (1) A recorded link file: its TUM output equals the firmware's
# trajectory, its JSON lines agree with an independent decoder (node-mavlink) on the same bytes
# (x, y and yaw mirrored back to the map frame), a corrupted copy shows CRC errors, and a file
# with commands is refused. (2) Live: the firmware on one pty, the monitor on another, bytes
# relayed between them; the monitor sends a signed "set pose" in map coordinates, gets its ACK
# and then sees the pose there. A capture-to-send report spliced into the recorded link shows in
# the view and the JSON lines as node-mavlink reads it.
source "$(dirname "$0")/lib.sh" "$1" "$2"
PEER_DIR=$3
[ -d "$PEER_DIR/node_modules/node-mavlink" ] || fail "node-mavlink is not installed in $PEER_DIR (run ./run setup)"
out="$WORK/monitor"
rm -rf "$out"; mkdir -p "$out"
MON="$BIN/harmoloc-monitor"

# ---- 1. a recorded link file --------------------------------------------------------------------
"$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --trajectory "$out/est.tum" \
  --link "$out/link.bin" --quiet > /dev/null
"$MON" --tum "$out/mon.tum" "$out/link.bin" > "$out/view.txt" 2> /dev/null
"$MON" --json "$out/link.bin" > "$out/mon.jsonl" 2> /dev/null
node "$PEER_DIR/link_peer.js" decode "$out/link.bin" - "$out/peer.json"
python3 - "$out" <<'PY'
import json, math, sys
out = sys.argv[1]
def fail(m): sys.exit(f"FAIL: {m}")
def tum(p):
    return [[float(v) for v in l.split()] for l in open(p) if l.strip() and not l.startswith("#")]
est, mon = tum(f"{out}/est.tum"), tum(f"{out}/mon.tum")
if len(est) != len(mon) or not est:
    fail(f"{len(mon)} monitor poses, {len(est)} in the firmware's trajectory")
for a, b in zip(est, mon):
    if abs(a[0] - b[0]) > 2e-6 or abs(a[1] - b[1]) > 2e-6 or abs(a[2] - b[2]) > 2e-6:
        fail(f"monitor TUM {b[:3]} differs from the trajectory {a[:3]}")
    ya, yb = 2 * math.atan2(a[6], a[7]), 2 * math.atan2(b[6], b[7])
    if abs(math.remainder(ya - yb, 2 * math.pi)) > 2e-5:
        fail(f"monitor yaw {yb} differs from the trajectory's {ya}")
lines = [json.loads(l) for l in open(f"{out}/mon.jsonl")]
peer = [f for f in json.load(open(f"{out}/peer.json"))["frames"] if f["msgid"] == 331]
if len(lines) != len(peer) or len(lines) != len(est):
    fail(f"{len(lines)} JSON lines, {len(peer)} ODOMETRY by node-mavlink, {len(est)} poses")
for j, p in zip(lines, peer):
    if set(j) < {"t", "x", "y", "yaw", "health"}:
        fail(f"JSON line without t, x, y, yaw, health: {j}")
    if abs(j["t"] - p["timeUsec"] / 1e6) > 1e-6 or abs(j["x"] - p["x"]) > 1e-6 \
            or abs(j["y"] + p["y"]) > 1e-6 or abs(math.remainder(j["yaw"] + p["yaw"], 2 * math.pi)) > 1e-5:
        fail(f"monitor {j} and node-mavlink {p} disagree")
if lines[-1]["health"] != "nominal":
    fail(f"health at the end {lines[-1]['health']}")
view = open(f"{out}/view.txt").read()
if f"{len(est)} ODOMETRY" not in view or "0 CRC errors" not in view:
    fail(f"summary: {view}")
print(f"recorded: {len(lines)} ODOMETRY decoded, equal to the trajectory and to node-mavlink")
PY
# A live board's capture-to-send report (NAMED_VALUE_FLOAT pair after a HEARTBEAT), spliced in
# after the third HEARTBEAT of the recorded link: the monitor shows it, node-mavlink agrees.
python3 - "$out/link.bin" "$out/latency.bin" <<'PY'
import struct, sys
def crc(data, c=0xFFFF):
    for b in data:
        t = (b ^ c) & 0xFF
        t = (t ^ (t << 4)) & 0xFF
        c = ((c >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4)) & 0xFFFF
    return c
def named(seq, name, value):
    payload = struct.pack("<If", 5000, value) + name.encode().ljust(10, b"\0")
    while len(payload) > 1 and payload[-1] == 0:
        payload = payload[:-1]
    head = bytes([0xFD, len(payload), 0, 0, seq, 1, 197, 251, 0, 0])
    c = crc(head[1:] + payload + bytes([170]))
    return head + payload + struct.pack("<H", c)
data = open(sys.argv[1], "rb").read()
i, heartbeats, at = 0, 0, None
while i < len(data):
    n = data[i + 1]
    msg = data[i + 7] | data[i + 8] << 8 | data[i + 9] << 16
    i += 12 + n + (13 if data[i + 2] & 1 else 0)
    if msg == 0:
        heartbeats += 1
        if heartbeats == 3:
            at = i
            break
assert at is not None, "fewer than 3 HEARTBEATs in the link"
open(sys.argv[2], "wb").write(data[:at] + named(200, "c2s_p50_ms", 7.25) + named(201, "c2s_max_ms", 11.5) + data[at:])
PY
"$MON" --json "$out/latency.bin" > "$out/latency.jsonl" 2> /dev/null
"$MON" "$out/latency.bin" > "$out/latency.txt" 2> /dev/null
node "$PEER_DIR/link_peer.js" decode "$out/latency.bin" - "$out/latency-peer.json"
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
def fail(m): sys.exit(f"FAIL: {m}")
lines = [json.loads(l) for l in open(f"{out}/latency.jsonl")]
with_latency = [l for l in lines if "capture_to_send_ms" in l]
if not with_latency or len(with_latency) == len(lines):
    fail(f"{len(with_latency)} of {len(lines)} JSON lines carry capture_to_send_ms (expected the ones after the report)")
if any(abs(l["capture_to_send_ms"] - 7.25) > 1e-6 for l in with_latency):
    fail(f"capture_to_send_ms {with_latency[0]['capture_to_send_ms']}, expected 7.25")
peer = [f for f in json.load(open(f"{out}/latency-peer.json"))["frames"] if f["msgid"] == 251]
if [(f["name"], f["value"]) for f in peer] != [("c2s_p50_ms", 7.25), ("c2s_max_ms", 11.5)]:
    fail(f"node-mavlink read {peer}")
view = open(f"{out}/latency.txt").read()
if "capture to send 7.2 ms median, 11.5 ms max" not in view:
    fail(f"the view does not show the latency: {view}")
print(f"latency report: in {len(with_latency)} of {len(lines)} JSON lines and the view, as node-mavlink reads it")
PY
python3 - "$out/link.bin" "$out/bad.bin" <<'PY'
import sys
data = bytearray(open(sys.argv[1], "rb").read())
for k in range(1, 6):
    data[k * len(data) // 7] ^= 0x40
open(sys.argv[2], "wb").write(data)
PY
"$MON" "$out/bad.bin" > "$out/bad.txt" 2> /dev/null
grep -q " 0 CRC errors" "$out/bad.txt" && fail "a corrupted capture shows no CRC error"
if "$MON" --relocalize "$out/link.bin" > /dev/null 2> "$out/err.txt"; then fail "commands to a file were taken"; fi
grep -q "commands need a serial device or pty" "$out/err.txt" || fail "no reason for refusing commands to a file: $(cat "$out/err.txt")"
if "$MON" "$out/missing.bin" > /dev/null 2> "$out/err.txt"; then fail "a missing source was taken"; fi
[ "$(wc -l < "$out/err.txt")" -eq 1 ] || fail "a missing source is not one line: $(cat "$out/err.txt")"
echo "OK: corrupted capture counted, commands to a file and a missing source refused"

# ---- 2. live: firmware and monitor on two ptys, relayed --------------------------------------
make_dataset 240 "$out/cut"
head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' > "$out/link.key"
chmod 600 "$out/link.key"
printf '[link]\nsigning_key_file = "link.key"\nsigning_state_file = "signing.state"\n' > "$out/harmoloc.toml"
python3 - "$BIN/harmoloc" "$MON" "$out" <<'PY'
import json, math, os, pty, select, subprocess, sys, time
harmoloc, mon, out = sys.argv[1:4]
def fail(m): sys.exit(f"FAIL: {m}")
fw_master, fw_slave = pty.openpty()
mon_master, mon_slave = pty.openpty()
fw = subprocess.Popen([harmoloc, "--dataset", f"{out}/cut", "--map", f"{out}/../tiny.hmap",
                       "--config", f"{out}/harmoloc.toml", "--link", os.ttyname(fw_slave),
                       "--realtime", "--quiet"], stdout=subprocess.DEVNULL)
# The monitor starts once the firmware talks, sends its command at once and reads 90 poses.
first = None
m = None
start = time.monotonic()
while True:
    if time.monotonic() - start > 40:
        fw.kill()
        if m: m.kill()
        fail("no end within 40 s")
    if m is None and fw.poll() is not None:
        fail(f"harmoloc ended (exit {fw.returncode}) before it said anything")
    r, _, _ = select.select([fw_master, mon_master], [], [], 0.02)
    if fw_master in r:
        try:
            data = os.read(fw_master, 65536)
        except OSError:
            data = b""
        if data and m is None:
            m = subprocess.Popen([mon, "--json", "--key", f"{out}/link.key", "--baud", "115200",
                                  "--set-pose", "2.0,1.0,0.5,0.001,0.001", "--count", "90",
                                  os.ttyname(mon_slave)],
                                 stdout=open(f"{out}/live.jsonl", "w"),
                                 stderr=open(f"{out}/live.err", "w"))
        if data:
            os.write(mon_master, data)
    if mon_master in r:
        try:
            data = os.read(mon_master, 65536)
        except OSError:
            data = b""
        if data:
            os.write(fw_master, data)
    if m is not None and m.poll() is not None:
        break
fw.terminate()
fw.wait(10)
err = open(f"{out}/live.err").read()
if m.returncode != 0:
    fail(f"monitor exit {m.returncode}: {err}")
if "set pose: ACCEPTED" not in err:
    fail(f"no ACCEPTED for set pose: {err}")
lines = [json.loads(l) for l in open(f"{out}/live.jsonl")]
if len(lines) != 90:
    fail(f"{len(lines)} JSON lines, expected 90")
# Right after the ACK the pose is where it was set (the filter then follows the boards again).
near = [l for l in lines if abs(l["x"] - 2.0) < 0.01 and abs(l["y"] - 1.0) < 0.01
        and abs(math.remainder(l["yaw"] - 0.5, 2 * math.pi)) < 0.01]
if not near:
    fail("no pose near the one set (2.0, 1.0, 0.5) in the map frame")
print(f"live: set pose ACCEPTED, {len(near)} of {len(lines)} poses at it; {err.strip()}")
PY
echo "OK: harmoloc-monitor"
