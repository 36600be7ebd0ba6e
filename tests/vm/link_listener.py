#!/usr/bin/env python3
"""The host's end of the VM's second serial line (QEMU -serial unix:PATH connects to it).

Records every byte the firmware sends into OUT; once the first bytes have arrived and DELAY_S
seconds have passed, writes the command frames given as hex (a MAVLink SET_POSE built by
tests/mavlink/link_peer.js) back down the line. Exits when QEMU closes the connection or after
TIMEOUT_S.

    link_listener.py SOCKET OUT COMMANDS_HEX DELAY_S TIMEOUT_S
"""
import os
import socket
import sys
import time


def main():
    path, out_path, commands_hex, delay_s, timeout_s = sys.argv[1:6]
    commands = bytes.fromhex(commands_hex)
    delay_s, timeout_s = float(delay_s), float(timeout_s)
    if os.path.exists(path):
        os.unlink(path)
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(path)
    server.listen(1)
    server.settimeout(timeout_s)
    print("listening", flush=True)  # the bench starts QEMU after this line
    start = time.monotonic()
    try:
        conn, _ = server.accept()
    except socket.timeout:
        print("link listener: QEMU never connected", file=sys.stderr)
        return 1
    conn.settimeout(0.2)
    first_byte_at = None
    sent = False
    total = 0
    with open(out_path, "wb") as out:
        while time.monotonic() - start < timeout_s:
            try:
                data = conn.recv(65536)
                if not data:
                    break
                out.write(data)
                total += len(data)
                if first_byte_at is None:
                    first_byte_at = time.monotonic()
            except socket.timeout:
                pass
            if not sent and first_byte_at is not None and time.monotonic() - first_byte_at >= delay_s:
                conn.sendall(commands)
                sent = True
    print(f"link listener: {total} bytes received, command {'sent' if sent else 'NOT sent'}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
