#!/usr/bin/env python3
"""The whole-loop run's two clocks (tests/vm/run_vm_tests.sh, docs/testbench.md).

vm_feeder plays a simulated dataset on the VM's CLOCK_MONOTONIC on the schedule
    vm(t) = start + slowdown * (t - origin)
and prints "FEEDER start_mono_ns=S origin_ns=O slowdown=K". When the VM keeps up, that schedule
is the map between the dataset's clock and the VM's. When it does not (a loaded or slow
emulator), the events go out late and in bursts, and the schedule would put every late frame's
pose at the wrong dataset time. So, given the feeder's events file (each frame's and CAN frame's
dataset time and the VM times its write() began and returned; the kernel stamps a frame in
between), the map runs through those points instead: the event's time while it is written,
linear between events, the schedule's slope beyond the first and last.

  loop_clock.py to-vm  FEEDER_LINE IN.tum OUT.tum [--events CSV] [--encoders CSV]
      labels onto the VM's clock, for training on its recording (with the recording's
      encoders.csv: only labels within its wheel odometry)
  loop_clock.py to-sim FEEDER_LINE IN.tum OUT.tum --truth TUM [--events CSV] [--late-s S]
      the VM's trajectory onto the dataset's clock (poses outside the truth's span dropped;
      --late-s puts every pose S seconds later, the check's negative control)
"""
import argparse
import bisect
import re
import sys

HEADER = 'kind,t_ns,sent_mono_ns,done_mono_ns'
SNAP_NS = 1000


def parse_feeder(line):
    f = dict(re.findall(r'(\w+)=(\S+)', line))
    return int(f['start_mono_ns']), int(f['origin_ns']), float(f['slowdown'])


def read_tum(path):
    rows = []
    for line in open(path):
        if line.strip() and not line.startswith('#'):
            rows.append(line.split())
    return rows


def read_events(path):
    """(vm_ns, t_ns) points in the order the events went out, two per event (its write() began,
    it returned); refuses a file that is not one."""
    vm, ts = [], []
    lines = open(path).read().splitlines()
    if not lines or lines[0] != HEADER:
        sys.exit(f'{path}: not a feeder events file (no header "{HEADER}")')
    for n, line in enumerate(lines[1:], 2):
        f = line.split(',')
        try:
            if len(f) != 4 or f[0] not in ('f', 'c'):
                raise ValueError
            t, began, done = int(f[1]), int(f[2]), int(f[3])
        except ValueError:
            sys.exit(f'{path}:{n}: not an event line')
        if done < began or (vm and (began < vm[-1] or t < ts[-1])):
            sys.exit(f'{path}:{n}: events out of order')
        vm += [began, done]
        ts += [t, t]
    if not vm:
        sys.exit(f'{path}: no events')
    return vm, ts


class Clock:
    def __init__(self, feeder_line, events_path):
        self.start, self.origin, self.k = parse_feeder(feeder_line)
        self.vm, self.ts = read_events(events_path) if events_path else ([], [])

    def to_vm(self, t_ns):
        if not self.ts:
            return self.start + self.k * (t_ns - self.origin)
        # Within a microsecond of an event (TUM keeps microseconds): that event's time, and the
        # last point with it (when its write() returned, when it was stamped). Otherwise no event
        # lies within the microsecond, so i is also where t_ns itself would go.
        i = bisect.bisect_right(self.ts, t_ns + SNAP_NS)
        if i > 0 and abs(self.ts[i - 1] - t_ns) <= SNAP_NS:
            t_ns = self.ts[i - 1]
        if i == 0:
            return self.vm[0] + self.k * (t_ns - self.ts[0])
        if i == len(self.ts) or self.ts[i - 1] == t_ns:
            return self.vm[i - 1] + self.k * (t_ns - self.ts[i - 1])
        t0, t1, v0, v1 = self.ts[i - 1], self.ts[i], self.vm[i - 1], self.vm[i]
        return v0 + (v1 - v0) * (t_ns - t0) / (t1 - t0)

    def to_sim(self, vm_ns):
        if not self.vm:
            return self.origin + (vm_ns - self.start) / self.k
        i = bisect.bisect_right(self.vm, vm_ns)
        if i == 0:
            return self.ts[0] + (vm_ns - self.vm[0]) / self.k
        if i == len(self.vm):
            return self.ts[-1] + (vm_ns - self.vm[-1]) / self.k
        v0, v1, t0, t1 = self.vm[i - 1], self.vm[i], self.ts[i - 1], self.ts[i]
        return t0 + (t1 - t0) * (vm_ns - v0) / (v1 - v0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('mode', choices=['to-vm', 'to-sim'])
    ap.add_argument('feeder_line', help='the feeder\'s "FEEDER start_mono_ns=..." line')
    ap.add_argument('src')
    ap.add_argument('dst')
    ap.add_argument('--events', help='the feeder\'s events file (' + HEADER + ')')
    ap.add_argument('--encoders', help='to-vm: the recording\'s encoders.csv')
    ap.add_argument('--truth', help='to-sim: the ground truth TUM (its span)')
    ap.add_argument('--late-s', type=float, default=0.0, help='to-sim: put every pose this late')
    a = ap.parse_args()
    clock = Clock(a.feeder_line, a.events)
    rows = read_tum(a.src)
    out = []
    if a.mode == 'to-vm':
        # The first encoder sample is read a cycle after the run's first CAN frame: the label
        # at the run's start falls before it.
        lo, hi = -1e300, 1e300
        if a.encoders:
            times = [int(l.split(',')[0]) for l in open(a.encoders).read().splitlines()[1:] if l]
            lo, hi = min(times), max(times)
        for r in rows:
            vm_ns = clock.to_vm(float(r[0]) * 1e9)
            if lo <= vm_ns <= hi:
                out.append(' '.join([f'{vm_ns * 1e-9:.6f}'] + r[1:]))
    else:
        if not a.truth:
            ap.error('to-sim needs --truth')
        truth = [float(r[0]) for r in read_tum(a.truth)]
        lo, hi = min(truth), max(truth)
        for r in rows:
            t = clock.to_sim(float(r[0]) * 1e9) * 1e-9 + a.late_s
            if lo <= t <= hi:
                out.append(' '.join([f'{t:.6f}'] + r[1:]))
    with open(a.dst, 'w') as f:
        f.write(''.join(l + '\n' for l in out))
    print(f'{len(out)} of {len(rows)} poses' + (' (on the feeder\'s events)' if a.events else ''),
          file=sys.stderr)


if __name__ == '__main__':
    main()
