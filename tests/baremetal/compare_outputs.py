#!/usr/bin/env python3
"""Runs the kernel tests on the host and on the emulated Cortex-M7 and compares their results.

Lines "v <name> <hex>" must be bit-identical; lines "t <name> <hex>" (doubles computed through
sin, cos or atan2, where glibc and newlib differ in the last bits) must agree within a relative
1e-12. Both runs must pass their own checks and print the same names.

  compare_outputs.py --emulator QEMU_WRAPPER --target kernel_tests.elf --host kernel_tests
"""
import argparse
import math
import struct
import subprocess
import sys

TRIG_TOLERANCE = 1e-12  # relative; the differences seen are below 1e-13 (docs/baremetal.md)


def run(command):
    proc = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    if proc.returncode != 0:
        failed = [l for l in proc.stdout.splitlines() if l.startswith("FAIL")]
        detail = failed[0] if failed else (proc.stderr.strip().splitlines() or ["no output"])[-1]
        sys.exit(f"{command[-1]} exited with {proc.returncode}: {detail}")
    values = {}
    for line in proc.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[0] in ("v", "t"):
            values[parts[1]] = (parts[0], int(parts[2], 16))
    return values


def as_double(bits):
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


def ulps(a_bits, b_bits):
    # Distance in representable doubles, for same-signed values.
    return abs(a_bits - b_bits)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--emulator", required=True)
    parser.add_argument("--target", required=True)
    parser.add_argument("--host", required=True)
    args = parser.parse_args()

    host = run([args.host])
    target = run([args.emulator, args.target])
    if host.keys() != target.keys():
        only = sorted(set(host) ^ set(target))
        sys.exit(f"host and target print different results: {', '.join(only)}")

    problems = []
    exact = trig = trig_differ = 0
    worst = (0.0, 0, "")
    for name in sorted(host):
        kind, h = host[name]
        _, t = target[name]
        if kind == "v":
            exact += 1
            if h != t:
                problems.append(f"{name}: host {h:#x}, target {t:#x} (must be bit-identical)")
            continue
        trig += 1
        if h == t:
            continue
        trig_differ += 1
        hd, td = as_double(h), as_double(t)
        rel = abs(hd - td) / max(abs(hd), abs(td))
        if not math.isfinite(rel) or rel > TRIG_TOLERANCE:
            problems.append(f"{name}: host {hd!r}, target {td!r} (relative {rel:.1e} > "
                            f"{TRIG_TOLERANCE:g})")
        elif rel > worst[0]:
            worst = (rel, ulps(h, t), name)

    if problems:
        for p in problems:
            print(p)
        sys.exit(f"{len(problems)} of {len(host)} results differ between host and target")
    print(f"host and target agree: {exact} results bit-identical, {trig} through sin/cos/atan2 of "
          f"which {trig - trig_differ} bit-identical and {trig_differ} within {TRIG_TOLERANCE:g}"
          + (f" (largest: {worst[2]}, relative {worst[0]:.1e}, {worst[1]} ulp)" if worst[2] else ""))


if __name__ == "__main__":
    main()
