#!/usr/bin/env bash
# The link output decoded by an independent MAVLink v2 implementation (node-mavlink, installed by
# ./run): zero CRC errors, ODOMETRY equal to the TUM trajectory. A corrupted copy must fail.
source "$(dirname "$0")/lib.sh" "$1" "$2"
DECODER_DIR=$3
[ -d "$DECODER_DIR/node_modules/node-mavlink" ] || fail "node-mavlink is not installed in $DECODER_DIR (run ./run setup)"
out="$WORK/mavlink"
rm -rf "$out"; mkdir -p "$out"
"$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --trajectory "$out/est.tum" --link "$out/link.bin" --quiet > /dev/null
node "$DECODER_DIR/decode_link.js" "$out/link.bin" "$out/est.tum"
# Negative control: one flipped byte in the middle must be caught by the decoder.
python3 - "$out/link.bin" "$out/bad.bin" <<'PY'
import sys
data = bytearray(open(sys.argv[1], 'rb').read())
data[len(data) // 2] ^= 0x40
open(sys.argv[2], 'wb').write(data)
PY
if node "$DECODER_DIR/decode_link.js" "$out/bad.bin" > /dev/null 2>&1; then fail "a corrupted link capture passed the decoder check"; fi
echo "OK: corrupted capture rejected"
