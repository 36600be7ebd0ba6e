#!/usr/bin/env node
// The peer on harmoloc's link, written with node-mavlink (an independent MAVLink v2
// implementation, signing included): builds the command frames a test sends and decodes what
// the firmware wrote back. The test script (tests/e2e/link_commands_test.sh) does the timing and
// the checks.
//
//   node link_peer.js frames SPEC.json OUT.json
//       SPEC: [{name, command, params: [7 numbers], sysid, compid, targetSystem, targetComponent,
//               key: hex or null (unsigned), linkId, timestampMs (signing time, Unix ms)}]
//             an entry with message: "timesync" is a TIMESYNC request (tc1 0, ts1: a decimal
//             string) instead of a COMMAND_LONG
//       OUT:  {name: hex of the whole frame}
//   node link_peer.js decode LINK_FILE KEY_HEX_OR_- OUT.json
//       OUT: {frames: [...], crcErrors, invalid}; each frame: msgid, seq, sysid, compid,
//            signed, signatureOk (null without a key), linkId, timestamp, and the fields of
//            COMMAND_ACK, HEARTBEAT, ODOMETRY (yaw from its quaternion) and TIMESYNC (tc1 and
//            ts1 as decimal strings)
//   node link_peer.js table PARSER_CPP
//       checks the firmware's table of CRC_EXTRA and payload lengths against node-mavlink's
'use strict';
const fs = require('fs');
const {
  MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV2, minimal, common,
} = require('node-mavlink');

const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY };

function frames(specPath, outPath) {
  const spec = JSON.parse(fs.readFileSync(specPath, 'utf8'));
  const out = {};
  spec.forEach((s, i) => {
    let msg;
    if (s.message === 'timesync') {
      msg = new common.TimeSync();
      msg.tc1 = BigInt(0);
      msg.ts1 = BigInt(s.ts1);
    } else {
      msg = new common.CommandLong();
      msg.command = s.command;
      for (let k = 0; k < 7; k += 1) msg[`_param${k + 1}`] = s.params[k];
    }
    msg.targetSystem = s.targetSystem;
    msg.targetComponent = s.targetComponent;
    const flags = s.key ? MavLinkProtocolV2.IFLAG_SIGNED : 0;
    const protocol = new MavLinkProtocolV2(s.sysid, s.compid, flags);
    let buffer = protocol.serialize(msg, i & 0xff);
    if (s.key) buffer = protocol.sign(buffer, s.linkId, Buffer.from(s.key, 'hex'), s.timestampMs);
    out[s.name] = buffer.toString('hex');
  });
  fs.writeFileSync(outPath, JSON.stringify(out, null, 1));
}

function decode(linkPath, keyHex, outPath) {
  const key = keyHex === '-' ? null : Buffer.from(keyHex, 'hex');
  let crcErrors = 0;
  const splitter = new MavLinkPacketSplitter({}, { onCrcError: () => { crcErrors += 1; } });
  const parser = new MavLinkPacketParser();
  const result = [];
  parser.on('data', (packet) => {
    const h = packet.header;
    const f = {
      msgid: h.msgid, seq: h.seq, sysid: h.sysid, compid: h.compid,
      signed: packet.signature !== null,
      signatureOk: packet.signature && key ? packet.signature.matches(key) : null,
      linkId: packet.signature ? packet.signature.linkId : null,
      timestamp: packet.signature ? packet.signature.timestamp : null,
    };
    const clazz = REGISTRY[h.msgid];
    if (clazz) {
      const d = packet.protocol.data(packet.payload, clazz);
      if (h.msgid === 77) {
        Object.assign(f, {
          command: d.command, result: d.result, resultParam2: d.resultParam2,
          targetSystem: d.targetSystem, targetComponent: d.targetComponent,
        });
      } else if (h.msgid === 0) {
        f.systemStatus = d.systemStatus;
      } else if (h.msgid === 331) {
        const [qw, qx, qy, qz] = d.q;
        Object.assign(f, {
          timeUsec: Number(d.timeUsec), x: d.x, y: d.y,
          yaw: Math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)),
          resetCounter: d.resetCounter,
        });
      } else if (h.msgid === 251) {
        Object.assign(f, { timeBootMs: d.timeBootMs, name: d.name, value: d.value });
      } else if (h.msgid === 111) {
        Object.assign(f, {
          tc1: d.tc1.toString(), ts1: d.ts1.toString(),
          targetSystem: d.targetSystem, targetComponent: d.targetComponent,
        });
      }
    }
    result.push(f);
  });
  parser.on('finish', () => {
    fs.writeFileSync(outPath, JSON.stringify({
      frames: result, crcErrors, invalid: splitter.invalidPackages,
      unknown: splitter.unknownPackagesCount,
    }));
  });
  fs.createReadStream(linkPath).pipe(splitter).pipe(parser);
}

function table(parserCpp) {
  const src = fs.readFileSync(parserCpp, 'utf8');
  let n = 0;
  let bad = 0;
  for (const m of src.matchAll(/\{(\d+), (\d+), (\d+)\},\s*\/\/ (\w+)/g)) {
    n += 1;
    const c = REGISTRY[Number(m[1])];
    if (!c || c.MAGIC_NUMBER !== Number(m[2]) || c.PAYLOAD_LENGTH !== Number(m[3])
        || c.MSG_NAME !== m[4]) {
      bad += 1;
      console.error(`FAIL: ${m[0].trim()} differs from node-mavlink (${c ? `${c.MSG_NAME} ${c.MAGIC_NUMBER} ${c.PAYLOAD_LENGTH}` : 'unknown id'})`);
    }
  }
  if (n < 10) { console.error(`FAIL: only ${n} table entries found in ${parserCpp}`); process.exit(1); }
  console.log(`message table: ${n} entries, ${bad} differ from node-mavlink`);
  process.exit(bad ? 1 : 0);
}

const [cmd, ...args] = process.argv.slice(2);
if (cmd === 'frames' && args.length === 2) frames(...args);
else if (cmd === 'decode' && args.length === 3) decode(...args);
else if (cmd === 'table' && args.length === 1) table(...args);
else {
  console.error('usage: link_peer.js frames SPEC OUT | decode LINK KEY|- OUT | table PARSER_CPP');
  process.exit(2);
}
