#!/usr/bin/env node
// Decodes a harmoloc link capture with node-mavlink (an independent MAVLink v2 implementation)
// and checks it against the firmware's TUM trajectory.
//   node decode_link.js [--expect-latency] LINK_FILE [TRAJECTORY.tum]
// Checks: no CRC errors, no unknown messages, HEARTBEAT at about 1 Hz, one ODOMETRY per pose, and
// ODOMETRY (MAV_FRAME_LOCAL_FRD) equal to the TUM pose (map frame, z up): x = x, y = -y, yaw = -yaw.
// Capture-to-send reports (NAMED_VALUE_FLOAT c2s_p50_ms and c2s_max_ms, a pair after a
// HEARTBEAT): well formed wherever they are; with --expect-latency (a live board) after every
// HEARTBEAT but the first.
'use strict';
const fs = require('fs');
const { MavLinkPacketSplitter, MavLinkPacketParser, minimal, common } = require('node-mavlink');

const args = process.argv.slice(2);
const expectLatency = args[0] === '--expect-latency';
if (expectLatency) args.shift();
const [linkPath, tumPath] = args;
if (!linkPath) {
  console.error('usage: decode_link.js [--expect-latency] LINK_FILE [TRAJECTORY.tum]');
  process.exit(2);
}
const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY };
let crcErrors = 0;
const splitter = new MavLinkPacketSplitter({}, { onCrcError: () => { crcErrors += 1; } });
const parser = new MavLinkPacketParser();
const counts = {};
const odometry = [];
const heartbeats = [];
let heartbeatsInSpan = 0;
const statustexts = [];
let lastSeq = null;
const named = [];
let previousId = null;
let seqGaps = 0;

parser.on('data', (packet) => {
  const id = packet.header.msgid;
  counts[id] = (counts[id] || 0) + 1;
  if (lastSeq !== null && packet.header.seq !== ((lastSeq + 1) & 0xff)) seqGaps += 1;
  lastSeq = packet.header.seq;
  const clazz = REGISTRY[id];
  if (!clazz) return;
  const data = packet.protocol.data(packet.payload, clazz);
  if (id === 331) odometry.push(data);
  if (id === 0) heartbeats.push(data);
  // The rate is checked over the ODOMETRY's own time span: before the first pose (waiting for a
  // set-pose, a slow start under an emulator) the link carries HEARTBEATs for a time nothing
  // in the stream dates.
  if (id === 0 && odometry.length > 0) heartbeatsInSpan += 1;
  if (id === 253) statustexts.push(data.text);
  if (id === 251) named.push({ name: data.name, value: data.value, afterHeartbeat: previousId });
  previousId = id;
});

const failures = [];
parser.on('finish', () => {
  const unknown = splitter.unknownPackagesCount;
  const invalid = splitter.invalidPackages;
  if (crcErrors > 0 || invalid > 0) failures.push(`${crcErrors} CRC errors, ${invalid} invalid packets`);
  if (unknown > 0) failures.push(`${unknown} packets of unknown message ids`);
  if (seqGaps > 0) failures.push(`${seqGaps} gaps in the sequence numbers`);
  if (heartbeats.length === 0) failures.push('no HEARTBEAT');
  // NAMED_VALUE_FLOAT pairs: the median right after a HEARTBEAT, then the maximum.
  let pairs = 0;
  for (let i = 0; i < named.length; i += 1) {
    const n = named[i];
    if (n.name !== 'c2s_p50_ms') { failures.push(`NAMED_VALUE_FLOAT ${n.name} where c2s_p50_ms was expected`); break; }
    const m = named[i + 1];
    if (!m || m.name !== 'c2s_max_ms' || m.afterHeartbeat !== 251 || n.afterHeartbeat !== 0) { failures.push('c2s_p50_ms not after a HEARTBEAT and before c2s_max_ms'); break; }
    // 0 is a frame stamped at or after its pose left (vivid stamps the end of a frame ahead of time).
    if (!(n.value >= 0 && n.value <= m.value && m.value < 10000)) { failures.push(`capture to send ${n.value} / ${m.value} ms out of order or range`); break; }
    pairs += 1;
    i += 1;
  }
  // Every HEARTBEAT after the first pose closes a period with poses in it (one may be cut short).
  if (expectLatency && (pairs === 0 || pairs < heartbeatsInSpan - 1)) failures.push(`${pairs} capture-to-send reports for ${heartbeatsInSpan} HEARTBEATs after the first pose`);
  if (odometry.length === 0) failures.push('no ODOMETRY');

  for (const o of odometry) {
    if (o.frameId !== 20 || o.childFrameId !== 12) { failures.push(`ODOMETRY frame ${o.frameId}/${o.childFrameId}, expected 20/12`); break; }
    if (!(o.quality >= -1 && o.quality <= 100)) { failures.push(`ODOMETRY quality ${o.quality} outside -1..100`); break; }
    if (!Number.isNaN(o.velocityCovariance[0])) { failures.push('velocity covariance should start with NaN (unknown)'); break; }
  }
  if (odometry.length > 1) {
    const t0 = Number(odometry[0].timeUsec) / 1e6;
    const t1 = Number(odometry[odometry.length - 1].timeUsec) / 1e6;
    const expected = Math.floor(t1 - t0) + 1;
    if (Math.abs(heartbeatsInSpan - expected) > 1) failures.push(`${heartbeatsInSpan} HEARTBEATs over the ${(t1 - t0).toFixed(1)} s of ODOMETRY (1 Hz expected)`);
  }

  if (tumPath) {
    const lines = fs.readFileSync(tumPath, 'utf8').split('\n').filter((l) => l.trim() && !l.startsWith('#'));
    if (lines.length !== odometry.length) failures.push(`${odometry.length} ODOMETRY messages but ${lines.length} TUM poses`);
    let worstPos = 0; let worstYaw = 0; let worstT = 0;
    const n = Math.min(lines.length, odometry.length);
    for (let i = 0; i < n; i += 1) {
      const f = lines[i].trim().split(/\s+/).map(Number);
      const o = odometry[i];
      const yawTum = 2 * Math.atan2(f[6], f[7]);
      const [qw, qx, qy, qz] = o.q;
      const yawFrd = Math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz));
      let dyaw = yawTum + yawFrd;
      dyaw = Math.atan2(Math.sin(dyaw), Math.cos(dyaw));
      worstPos = Math.max(worstPos, Math.abs(o.x - f[1]), Math.abs(-o.y - f[2]));
      worstYaw = Math.max(worstYaw, Math.abs(dyaw));
      worstT = Math.max(worstT, Math.abs(Number(o.timeUsec) / 1e6 - f[0]));
    }
    // TUM keeps 6 decimals (1 um); float32 keeps ~0.2 um at a few metres.
    if (worstPos > 2e-6) failures.push(`ODOMETRY position differs from TUM by ${worstPos} m`);
    if (worstYaw > 1e-5) failures.push(`ODOMETRY yaw differs from TUM by ${worstYaw} rad`);
    if (worstT > 1.5e-6) failures.push(`ODOMETRY time differs from TUM by ${worstT} s`);
    console.log(`compared ${n} poses: max |dpos| ${worstPos.toExponential(2)} m, max |dyaw| ${worstYaw.toExponential(2)} rad`);
  }
  const byName = Object.entries(counts).map(([id, c]) => `#${id} x${c}`).join(', ');
  console.log(`decoded ${splitter.validPackages} packets (${byName}); CRC errors ${crcErrors}; status texts: ${JSON.stringify(statustexts)}`);
  if (pairs > 0) {
    const p50 = named.filter((n) => n.name === 'c2s_p50_ms').map((n) => n.value).sort((a, b) => a - b);
    const max = Math.max(...named.filter((n) => n.name === 'c2s_max_ms').map((n) => n.value));
    console.log(`capture to send: ${pairs} reports, median of the periods' medians ${p50[(p50.length - 1) >> 1].toFixed(2)} ms, largest maximum ${max.toFixed(2)} ms`);
  }
  if (failures.length) {
    for (const f of failures) console.error(`FAIL: ${f}`);
    process.exit(1);
  }
  console.log('OK');
});

fs.createReadStream(linkPath).pipe(splitter).pipe(parser);
