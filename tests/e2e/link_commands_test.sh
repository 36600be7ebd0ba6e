#!/usr/bin/env bash
# The link's inbound side end to end. An independent peer (node-mavlink, tests/mavlink/
# link_peer.js) builds signed and unsigned commands; they go to the firmware through a pty,
# paced at the recording's rate, between bursts of garbage. Checked: the COMMAND_ACKs (order,
# results, targets), what each command did to the ODOMETRY that follows it, that every frame
# the firmware sends is signed with the key, the inbound counters in the stats, and that the
# trajectory still equals the ODOMETRY stream. Then the same through --link-in (a file, no
# key: unsigned commands are taken), and bad key files at start-up.
source "$(dirname "$0")/lib.sh" "$1" "$2"
PEER_DIR=$3
SRC_ROOT=$(cd "$(dirname "$0")/../.." && pwd)
[ -d "$PEER_DIR/node_modules/node-mavlink" ] || fail "node-mavlink is not installed in $PEER_DIR (run ./run setup)"
out="$WORK/link_commands"
rm -rf "$out"; mkdir -p "$out"

# The firmware's CRC_EXTRA table agrees with node-mavlink's.
node "$PEER_DIR/link_peer.js" table "$SRC_ROOT/firmware/src/mavlink_parser.cpp"

make_dataset 150 "$out/cut"
python3 - "$BIN/harmoloc" "$out" "$PEER_DIR/link_peer.js" <<'PY'
import json, os, pty, random, select, subprocess, sys, time
harmoloc, out, peer = sys.argv[1:4]

def fail(msg):
    sys.exit(f"FAIL: {msg}")

def node(*args):
    subprocess.run(["node", peer, *args], check=True)

def load_json(path):
    with open(path) as f:
        return json.load(f)

def stats_inbound(path):
    return load_json(path)["inbound"]

def tum(path):
    rows = []
    for line in open(path):
        if line.strip() and not line.startswith("#"):
            rows.append([float(v) for v in line.split()])
    return rows

def garbage(n, rng):
    return bytes(0xFD if rng.random() < 0.15 else rng.randrange(256) for _ in range(n))

# ---- 1. a signed link through a pty ------------------------------------------------------------
key = os.urandom(32)
wrong_key = os.urandom(32)
with open(f"{out}/link.key", "w") as f:
    f.write(key.hex() + "\n")
os.chmod(f"{out}/link.key", 0o600)
with open(f"{out}/harmoloc.toml", "w") as f:
    f.write('[link]\naccept_system_ids = [255]\naccept_component_ids = [190]\n'
            'signing_key_file = "link.key"\nsigning_state_file = "signing.state"\nlink_id = 5\n')
if os.path.exists(f"{out}/signing.state"):
    os.remove(f"{out}/signing.state")

now_ms = int(time.time() * 1000)
def command(name, cmd, params, signed_with=key, sysid=255, compid=190, dt_ms=0, target=(1, 197)):
    return dict(name=name, command=cmd, params=(list(params) + [0] * 7)[:7], sysid=sysid,
                compid=compid, targetSystem=target[0], targetComponent=target[1],
                key=signed_with.hex() if signed_with else None, linkId=0, timestampMs=now_ms + dt_ms)

POSE = [2.0, -1.0, 0.5, 0.001, 0.001]  # x, y, yaw in LOCAL_FRD; tight spreads
spec = [
    command("unsigned_pose", 31011, POSE, signed_with=None),
    command("wrong_key_pose", 31011, POSE, signed_with=wrong_key, dt_ms=1),
    command("other_source", 31011, POSE, sysid=42, dt_ms=2),
    command("set_pose", 31011, POSE, dt_ms=3),
    command("request_heartbeat", 512, [0], dt_ms=4),
    command("request_other", 512, [999], dt_ms=5),
    command("unsupported", 400, [], dt_ms=6),
    command("other_target", 31010, [], dt_ms=7, target=(9, 197)),
    command("relocalize", 31010, [], dt_ms=8),
    command("request_odometry", 512, [331], dt_ms=9),
    # An autopilot's TIMESYNC request (its ids are not accepted for commands; answering changes
    # nothing, so it is answered, signed as the link requires).
    dict(name="timesync", message="timesync", ts1="1234567890123", sysid=1, compid=1,
         targetSystem=0, targetComponent=0, key=key.hex(), linkId=0, timestampMs=now_ms + 10),
]
with open(f"{out}/spec.json", "w") as f:
    json.dump(spec, f)
node("frames", f"{out}/spec.json", f"{out}/frames.json")
frames = {k: bytes.fromhex(v) for k, v in load_json(f"{out}/frames.json").items()}

rng = random.Random(8)
odo_split = len(frames["request_odometry"]) // 2
# (seconds after the firmware's first byte, what the peer sends)
schedule = [
    (0.3, garbage(1500, rng)),
    (0.5, frames["unsigned_pose"]),
    (0.7, frames["wrong_key_pose"]),
    (0.9, frames["other_source"]),
    (1.1, frames["set_pose"]),
    (1.4, frames["set_pose"]),  # replayed
    (1.7, frames["request_heartbeat"]),
    (2.0, frames["request_other"]),
    (2.3, frames["unsupported"]),
    (2.6, frames["other_target"]),
    (2.9, garbage(1500, rng) + frames["relocalize"]),
    (3.1, frames["timesync"]),
    (3.3, frames["request_odometry"][:odo_split]),  # one frame split over two writes
    (3.45, frames["request_odometry"][odo_split:]),
]
sent = sum(len(b) for _, b in schedule)

master, slave = pty.openpty()
p = subprocess.Popen([harmoloc, "--dataset", f"{out}/cut", "--map", f"{out}/../tiny.hmap",
                      "--config", f"{out}/harmoloc.toml", "--link", os.ttyname(slave),
                      "--trajectory", f"{out}/est.tum", "--stats", f"{out}/stats.json",
                      "--realtime", "--quiet"], stdout=subprocess.DEVNULL)
data = bytearray()
start = time.monotonic()
first = None
pending = list(schedule)
while True:
    ready, _, _ = select.select([master], [], [], 0.02)
    if ready:
        try:
            chunk = os.read(master, 65536)
        except OSError:
            chunk = b""
        if chunk and first is None:
            first = time.monotonic()
        data += chunk
    elif p.poll() is not None:
        break
    while first is not None and pending and time.monotonic() - first >= pending[0][0]:
        os.write(master, pending.pop(0)[1])
    if time.monotonic() - start > 40:
        p.kill()
        fail("harmoloc did not finish within 40 s")
if p.returncode != 0:
    fail(f"harmoloc exit {p.returncode}")
if pending:
    fail(f"the run ended before {len(pending)} scheduled sends")
with open(f"{out}/link.bin", "wb") as f:
    f.write(data)
print(f"pty: {len(data)} bytes from the firmware, {sent} bytes sent to it")

node("decode", f"{out}/link.bin", key.hex(), f"{out}/decoded.json")
d = load_json(f"{out}/decoded.json")
fs = d["frames"]
if d["crcErrors"] or d["invalid"] or d["unknown"]:
    fail(f"decoder: {d['crcErrors']} CRC errors, {d['invalid']} invalid, {d['unknown']} unknown")
unsigned = [f for f in fs if not f["signed"] or not f["signatureOk"] or f["linkId"] != 5]
if unsigned:
    fail(f"{len(unsigned)} of {len(fs)} frames not signed with the key on link 5: {unsigned[0]}")
stamps = [f["timestamp"] for f in fs]
if any(b <= a for a, b in zip(stamps, stamps[1:])):
    fail("signature timestamps do not rise strictly")

acks = [(i, f) for i, f in enumerate(fs) if f["msgid"] == 77]
got = [(f["command"], f["result"]) for _, f in acks]
want = [(31011, 0), (512, 0), (512, 2), (400, 3), (31010, 0), (512, 0)]
if got != want:
    fail(f"COMMAND_ACKs {got}, expected {want}")
if any((f["targetSystem"], f["targetComponent"]) != (255, 190) for _, f in acks):
    fail("an ACK is not addressed to 255/190")

def next_of(i, msgid):
    return next((f for f in fs[i + 1:] if f["msgid"] == msgid), None)

def previous_of(i, msgid):
    return next((f for f in reversed(fs[:i]) if f["msgid"] == msgid), None)

# set pose: the ODOMETRY right after the ACK is at the commanded pose, and a reset is counted.
i_pose = acks[0][0]
o = next_of(i_pose, 331)
before = previous_of(i_pose, 331)
if o is None or abs(o["x"] - 2.0) > 2e-3 or abs(o["y"] + 1.0) > 2e-3 or abs(o["yaw"] - 0.5) > 2e-3:
    fail(f"ODOMETRY after set pose is {o}, expected x 2.0, y -1.0, yaw 0.5")
if before is not None and o["resetCounter"] != (before["resetCounter"] + 1) % 256:
    fail(f"reset_counter {before['resetCounter']} -> {o['resetCounter']} over set pose")
print(f"set pose: ODOMETRY x {o['x']:.5f} y {o['y']:.5f} yaw {o['yaw']:.5f}")
# request HEARTBEAT / ODOMETRY: the message follows its ACK at once.
if fs[acks[1][0] + 1]["msgid"] != 0:
    fail("no HEARTBEAT right after the ACK of its request")
# (this cycle's scheduled HEARTBEAT or a STATUSTEXT may come between: publish sends them first)
after = fs[acks[5][0] + 1:]
k = next((j for j, f in enumerate(after) if f["msgid"] not in (0, 253)), len(after))
if k == len(after) or after[k]["msgid"] != 331:
    fail("no ODOMETRY right after the ACK of its request")
# relocalize: a reset, and result_param2 says where the particles went (1 fix, 2 map).
i_reloc = acks[4][0]
if acks[4][1]["resultParam2"] not in (1, 2):
    fail(f"relocalize result_param2 {acks[4][1]['resultParam2']}")
ro, rb = next_of(i_reloc, 331), previous_of(i_reloc, 331)
if ro["resetCounter"] != (rb["resetCounter"] + 1) % 256:
    fail("relocalize did not count a reset")

# TIMESYNC: answered once, to the autopilot, with its ts1 and our time (ns, ODOMETRY's clock).
ts = [f for f in fs if f["msgid"] == 111]
if len(ts) != 1 or ts[0]["ts1"] != "1234567890123" or int(ts[0]["tc1"]) <= 0 \
        or (ts[0]["targetSystem"], ts[0]["targetComponent"]) != (1, 1):
    fail(f"TIMESYNC answers {ts}, expected one with ts1 1234567890123 to 1/1")
odo_before = previous_of(fs.index(ts[0]), 331)
if odo_before is not None and abs(int(ts[0]["tc1"]) / 1000 - odo_before["timeUsec"]) > 1e6:
    fail(f"TIMESYNC tc1 {ts[0]['tc1']} ns is not on ODOMETRY's clock ({odo_before['timeUsec']} us)")
print(f"timesync: tc1 {ts[0]['tc1']} ns for ts1 {ts[0]['ts1']}")

# The trajectory is the ODOMETRY stream, commands included.
odo = [f for f in fs if f["msgid"] == 331]
rows = tum(f"{out}/est.tum")
if len(rows) != len(odo):
    fail(f"{len(odo)} ODOMETRY messages but {len(rows)} TUM poses")
worst = max(max(abs(f["x"] - r[1]), abs(-f["y"] - r[2])) for f, r in zip(odo, rows))
if worst > 2e-6:
    fail(f"ODOMETRY differs from the trajectory by {worst} m")

s = stats_inbound(f"{out}/stats.json")
expect = dict(bytes_in=sent, commands_accepted=4, commands_refused=2, rejected_unsigned=1,
              rejected_bad_signature=1, rejected_replay=1, rejected_source=1, ignored_messages=1,
              timesync_requests=1)
wrong = {k: (s[k], v) for k, v in expect.items() if s[k] != v}
if wrong:
    fail(f"inbound counters (got, expected): {wrong}; all: {s}")
if s["frames_in"] != 12 or s["garbage_bytes"] < 2500:  # 11 frames, one sent twice
    fail(f"inbound counters: {s}")
print(f"inbound: {s}")

# ---- 1b. the restart: the set-pose captured in part 1 is a replay for the next run too --------
# (issue 16: the replay protection lived in memory only, and the captured command moved the pose
# again after a restart). The state file holds a high-water mark above every timestamp run 1
# sent or accepted. A frame dated a year ahead is refused and moves nothing; a fresh one is taken.
state = open(f"{out}/signing.state").read().split()
captured_ts = (now_ms + 3) * 100 - 1420070400 * 100000  # 10 us since 2015-01-01
if state[:3] != ["harmoloc-signing-state", "1", "high_water"] or int(state[3]) <= captured_ts:
    fail(f"signing state after run 1: {state[:6]}")
spec3 = [command("year_ahead", 31011, POSE, dt_ms=365 * 86400 * 1000),
         command("fresh", 31011, [1.0, -1.0, 0.0, 0.001, 0.001], dt_ms=20000)]
with open(f"{out}/spec3.json", "w") as f:
    json.dump(spec3, f)
node("frames", f"{out}/spec3.json", f"{out}/frames3.json")
frames3 = {k: bytes.fromhex(v) for k, v in load_json(f"{out}/frames3.json").items()}
with open(f"{out}/restart_in.bin", "wb") as f:
    f.write(frames["set_pose"] + frames3["year_ahead"] + frames3["fresh"])
r = subprocess.run([harmoloc, "--dataset", f"{out}/cut", "--map", f"{out}/../tiny.hmap",
                    "--config", f"{out}/harmoloc.toml", "--link", f"{out}/restart_link.bin",
                    "--link-in", f"{out}/restart_in.bin", "--stats", f"{out}/restart_stats.json",
                    "--quiet"], stdout=subprocess.DEVNULL)
if r.returncode != 0:
    fail(f"harmoloc after the restart: exit {r.returncode}")
s = stats_inbound(f"{out}/restart_stats.json")
if (s["rejected_replay"], s["rejected_future"], s["commands_accepted"]) != (1, 1, 1):
    fail(f"after the restart: replay {s['rejected_replay']}, future {s['rejected_future']}, "
         f"accepted {s['commands_accepted']} (expected 1, 1, 1); all: {s}")
print(f"restart: captured set-pose rejected as a replay, year-ahead frame rejected, fresh one taken")

# ---- 2. --link-in from a file, no key: unsigned commands are taken, output is unsigned ---------
spec2 = [command("set_pose", 31011, POSE, signed_with=None),
         command("request_heartbeat", 512, [0], signed_with=None)]
with open(f"{out}/spec2.json", "w") as f:
    json.dump(spec2, f)
node("frames", f"{out}/spec2.json", f"{out}/frames2.json")
frames2 = {k: bytes.fromhex(v) for k, v in load_json(f"{out}/frames2.json").items()}
inbound = garbage(700, rng) + frames2["set_pose"] + garbage(300, rng) + frames2["request_heartbeat"]
with open(f"{out}/in.bin", "wb") as f:
    f.write(inbound)
r = subprocess.run([harmoloc, "--dataset", f"{out}/cut", "--map", f"{out}/../tiny.hmap",
                    "--link", f"{out}/file_link.bin", "--link-in", f"{out}/in.bin",
                    "--trajectory", f"{out}/file_est.tum", "--stats", f"{out}/file_stats.json",
                    "--quiet"], stdout=subprocess.DEVNULL)
if r.returncode != 0:
    fail(f"harmoloc --link-in exit {r.returncode}")
node("decode", f"{out}/file_link.bin", "-", f"{out}/file_decoded.json")
fs = load_json(f"{out}/file_decoded.json")["frames"]
if any(f["signed"] for f in fs):
    fail("frames signed without a key")
acks = [(i, f) for i, f in enumerate(fs) if f["msgid"] == 77]
if [(f["command"], f["result"]) for _, f in acks] != [(31011, 0), (512, 0)]:
    fail(f"--link-in ACKs: {[(f['command'], f['result']) for _, f in acks]}")
o = next_of(acks[0][0], 331)
if o is None or abs(o["x"] - 2.0) > 2e-3 or abs(o["y"] + 1.0) > 2e-3:
    fail(f"--link-in: ODOMETRY after set pose is {o}")
s = stats_inbound(f"{out}/file_stats.json")
if s["bytes_in"] != len(inbound) or s["commands_accepted"] != 2 or s["frames_in"] != 2:
    fail(f"--link-in inbound counters: {s}")
print("--link-in: OK")
PY

# ---- 3. bad key files stop start-up with one line ------------------------------------------------
for case in missing short zeros; do
  cfg="$out/bad_$case.toml"
  case $case in
    missing) printf '[link]\nsigning_key_file = "nowhere.key"\n' > "$cfg" ;;
    short) printf '0123456789abcdef\n' > "$out/short.key"; printf '[link]\nsigning_key_file = "short.key"\n' > "$cfg" ;;
    zeros) head -c 32 /dev/zero > "$out/zeros.key"; printf '[link]\nsigning_key_file = "zeros.key"\n' > "$cfg" ;;
  esac
  status=0
  "$BIN/harmoloc" --dataset "$out/cut" --map "$WORK/tiny.hmap" --config "$cfg" --quiet > /dev/null 2> "$out/err_$case.txt" || status=$?
  [ "$status" -eq 2 ] || fail "bad key file ($case): exit $status, expected 2"
  [ "$(wc -l < "$out/err_$case.txt")" -eq 1 ] || fail "bad key file ($case): not one line: $(cat "$out/err_$case.txt")"
  grep -q "link.signing_key_file" "$out/err_$case.txt" || fail "bad key file ($case): $(cat "$out/err_$case.txt")"
done
# A key without a state file, or a damaged state file, stops start-up too (no guessing at the
# replay protection).
status=0
printf '[link]\nsigning_key_file = "link.key"\n' > "$out/no_state.toml"
"$BIN/harmoloc" --dataset "$out/cut" --map "$WORK/tiny.hmap" --config "$out/no_state.toml" --quiet > /dev/null 2> "$out/err_no_state.txt" || status=$?
[ "$status" -eq 2 ] && [ "$(wc -l < "$out/err_no_state.txt")" -eq 1 ] && grep -q "needs link.signing_state_file" "$out/err_no_state.txt" || fail "key without a state file: exit $status: $(cat "$out/err_no_state.txt")"
printf 'harmoloc-signing-state 1\nhigh_water banana\n' > "$out/damaged.state"
printf '[link]\nsigning_key_file = "link.key"\nsigning_state_file = "damaged.state"\n' > "$out/damaged.toml"
status=0
"$BIN/harmoloc" --dataset "$out/cut" --map "$WORK/tiny.hmap" --config "$out/damaged.toml" --quiet > /dev/null 2> "$out/err_damaged.txt" || status=$?
[ "$status" -eq 2 ] && [ "$(wc -l < "$out/err_damaged.txt")" -eq 1 ] && grep -q "damaged.state: line 2: high_water" "$out/err_damaged.txt" || fail "damaged state file: exit $status: $(cat "$out/err_damaged.txt")"
echo "OK"
