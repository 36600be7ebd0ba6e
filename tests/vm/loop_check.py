#!/usr/bin/env python3
"""The whole loop's verdict (tests/vm/run_vm_tests.sh, docs/testbench.md).

  loop_check.py TRUTH.tum HOST.tum VM.tum [VM-LINE ...]

Each estimate pose (TUM, on the dataset's clock) is compared with the ground truth linearly
interpolated at its time (as harmoloc-report does; poses outside the truth's span are not
scored); the position RMS error of the host replay and of the VM run. Passes when every VM line
(the boots' "VMTEST-END ... | FEEDER done ..." summaries) says rc=0 and frames, the VM scored at
least 80 % as many poses as the host replay, and the VM's position RMS error is within 1 cm of
the host replay's or within 1.5 times it. Exit status 0 or 1.
"""
import bisect
import math
import re
import sys


def read_tum(path):
    rows = []
    for line in open(path):
        f = line.split()
        if len(f) >= 3 and not line.startswith('#'):
            rows.append((float(f[0]), float(f[1]), float(f[2])))
    return rows


def score(truth, est):
    ts = [r[0] for r in truth]
    errs = []
    for t, x, y in est:
        i = bisect.bisect_left(ts, t)
        if i == 0 and t < ts[0] or i >= len(ts):
            continue
        if ts[i] == t:
            gx, gy = truth[i][1], truth[i][2]
        else:
            (t0, x0, y0), (t1, x1, y1) = truth[i - 1], truth[i]
            a = (t - t0) / (t1 - t0)
            gx, gy = x0 + a * (x1 - x0), y0 + a * (y1 - y0)
        errs.append(math.hypot(x - gx, y - gy) * 100.0)
    if not errs:
        return 0, None, None
    return len(errs), math.sqrt(sum(e * e for e in errs) / len(errs)), max(errs)


truth = read_tum(sys.argv[1])
(hn, h, hmax), (vn, v, vmax) = score(truth, read_tum(sys.argv[2])), score(truth, read_tum(sys.argv[3]))
bad = []


def need(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        bad.append(what)


for line in sys.argv[4:]:
    f = dict(re.findall(r'(\w+)=(\S+)', line))
    need(f.get("rc") == "0" and int(f.get("frames", "0")) > 0, f"in the VM: {line}")
need(vn > 0 and vn >= 0.8 * hn, f"VM poses scored {vn} (host replay {hn})")
if v is None or h is None:
    need(False, "no pose scored")
else:
    need(v <= h + 1.0 or v <= 1.5 * h,
         f"position RMS error: VM {v:.2f} cm, host replay {h:.2f} cm (within 1 cm, or 1.5 times); "
         f"max VM {vmax:.2f} cm, host {hmax:.2f} cm")
sys.exit(1 if bad else 0)
