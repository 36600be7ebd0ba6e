#!/usr/bin/env python3
"""The whole-loop run's two clocks (tests/vm/run_vm_tests.sh, docs/testbench.md).

vm_feeder plays a simulated dataset on the VM's CLOCK_MONOTONIC: a dataset time t is played at
    vm(t) = start + slowdown * (t - origin)
and prints "FEEDER start_mono_ns=S origin_ns=O slowdown=K". This moves TUM files between the
dataset's clock and the VM's:

  loop_clock.py to-vm  FEEDER_LINE IN.tum OUT.tum [ENCODERS.csv]  (labels, for training on the
                                                            VM's recording; within its odometry)
  loop_clock.py to-sim FEEDER_LINE IN.tum OUT.tum TRUTH.tum (the VM's trajectory, for the report;
                                                            poses outside the truth's span dropped)
"""
import re
import sys


def parse_feeder(line):
    f = dict(re.findall(r'(\w+)=(\S+)', line))
    return int(f['start_mono_ns']), int(f['origin_ns']), float(f['slowdown'])


def read_tum(path):
    rows = []
    for line in open(path):
        if line.strip() and not line.startswith('#'):
            rows.append(line.split())
    return rows


def main():
    mode, feeder, src, dst = sys.argv[1:5]
    start, origin, k = parse_feeder(feeder)
    rows = read_tum(src)
    out = []
    if mode == 'to-vm':
        # With a recording's encoders.csv: only labels within its wheel odometry (the first
        # sample is read a cycle after the run's first CAN frame, the label at the run's start
        # falls before it).
        lo, hi = -1e300, 1e300
        if len(sys.argv) > 5:
            times = [int(l.split(',')[0]) for l in open(sys.argv[5]).read().splitlines()[1:] if l]
            lo, hi = min(times), max(times)
        for r in rows:
            t = float(r[0])
            vm_ns = start + k * (t * 1e9 - origin)
            if lo <= vm_ns <= hi:
                out.append(' '.join([f'{vm_ns * 1e-9:.6f}'] + r[1:]))
    elif mode == 'to-sim':
        truth = [float(r[0]) for r in read_tum(sys.argv[5])]
        lo, hi = min(truth), max(truth)
        for r in rows:
            t_ns = origin + (float(r[0]) * 1e9 - start) / k
            t = t_ns * 1e-9
            if lo <= t <= hi:
                out.append(' '.join([f'{t:.6f}'] + r[1:]))
    else:
        sys.exit(f'unknown mode {mode}')
    with open(dst, 'w') as f:
        f.write(''.join(l + '\n' for l in out))
    print(f'{len(out)} of {len(rows)} poses', file=sys.stderr)


if __name__ == '__main__':
    main()
