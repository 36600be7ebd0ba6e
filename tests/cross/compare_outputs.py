#!/usr/bin/env python3
"""Compares harmoloc-crosscheck's output on a target (under qemu-user) with the host build's.

  compare_outputs.py HOST_BIN TARGET_BIN [CYCLES] -- EMULATOR...

Every integer (areas, flags, health, the link's byte count) must be equal. Floating-point values
(fix, pose, covariance) must agree within ABS_TOL + REL_TOL * |host value|; the largest
differences are printed. The link's CRC-32 (the MAVLink bytes) must be equal too when every
floating-point value is bit-identical; otherwise the float32 fields of ODOMETRY may round
differently and it is only reported. docs/cross-build.md states the tolerance.
"""
import subprocess
import sys

ABS_TOL = 1e-7
REL_TOL = 1e-6


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        sys.exit("FAIL: %s exited %d: %s" % (" ".join(cmd), r.returncode, r.stderr.strip()[-500:]))
    return r.stdout.splitlines()


def tokens(line):
    out = []
    for t in line.split():
        try:
            out.append(int(t))
        except ValueError:
            try:
                out.append(float(t))
            except ValueError:
                out.append(t)
    return out


def main():
    args = sys.argv[1:]
    sep = args.index("--") if "--" in args else len(args)
    host_bin, target_bin = args[0], args[1]
    cycles = args[2] if sep > 2 else "60"
    emulator = args[sep + 1:]
    host = run([host_bin, cycles])
    target = run(emulator + [target_bin, cycles])
    if len(host) != len(target):
        sys.exit("FAIL: %d lines on the host, %d on the target" % (len(host), len(target)))
    worst = []  # (abs diff, line, field index, host, target)
    identical = True
    bad = 0
    for n, (h, t) in enumerate(zip(host[:-1], target[:-1])):
        a, b = tokens(h), tokens(t)
        if len(a) != len(b) or [type(x) for x in a] != [type(y) for y in b]:
            print("FAIL line %d differs in shape:\n  host   %s\n  target %s" % (n, h, t))
            bad += 1
            continue
        for i, (x, y) in enumerate(zip(a, b)):
            if isinstance(x, float):
                d = abs(x - y)
                if x != y:
                    identical = False
                    worst.append((d, n, i, x, y))
                if d > ABS_TOL + REL_TOL * abs(x):
                    print("FAIL line %d field %d: host %r target %r (diff %.3g)" % (n, i, x, y, d))
                    bad += 1
            elif x != y:
                print("FAIL line %d field %d: host %r target %r" % (n, i, x, y))
                bad += 1
    floats = sum(isinstance(x, float) for line in host[:-1] for x in tokens(line))
    print("%d cycles, %d floating-point values: %s" % (
        len(host) - 1, floats,
        "all bit-identical" if identical else "%d differ, largest %.3g" % (len(worst), max(worst)[0])))
    for d, n, i, x, y in sorted(worst, reverse=True)[:5]:
        print("  cycle %d field %d: host %r target %r (diff %.3g)" % (n, i, x, y, d))
    print("link: host %s | target %s" % (host[-1], target[-1]))
    if host[-1] != target[-1]:
        if identical:
            print("FAIL: same values but different MAVLink bytes")
            bad += 1
        else:
            print("(the MAVLink bytes differ with the floating-point values above)")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
