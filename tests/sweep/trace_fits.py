#!/usr/bin/env python3
"""Sorts a sweep's floor-roam frames with a large error by what the boards said (docs/sweep.md).

For each seed-N-floor-roam1.csv in TRACE_DIR (harmoloc-sweep --parts floor --trace TRACE_DIR),
from the 61st valid frame on, the frames whose error exceeds --error-cm (of those on which the
cycle weighed the boards: the others have no fit) are split by the boards'
fit at the truth against the estimate (truth_nats - estimate_nats, floor_fit in the map's
trained noise): within --nats of each other (the boards cannot tell the two apart), the truth
better (evidence the filter did not follow), the estimate better (the map is wrong at the
truth). Also per scene: the published position spread (median) and the share of frames whose
error is within three of it."""
import argparse
import csv
import glob
import math
import re
import statistics
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trace_dir", help="the folder harmoloc-sweep --trace wrote")
    ap.add_argument("--error-cm", type=float, default=10.0, help="a large error (default 10)")
    ap.add_argument("--nats", type=float, default=2.0, help="fits this close are equal (default 2)")
    args = ap.parse_args()
    paths = glob.glob(args.trace_dir + "/seed-*-floor-roam1.csv")
    if not paths:
        print(f"trace_fits: no seed-N-floor-roam1.csv in {args.trace_dir}", file=sys.stderr)
        return 1
    seed_of = lambda p: int(re.findall(r"seed-(\d+)-floor", p)[0])
    print("seed  RMSE cm  frames > error  equal  truth better  estimate better  "
          "mean truth-estimate nats  spread cm  within 3 spreads %")
    totals = [0, 0, 0, 0]
    for path in sorted(paths, key=seed_of):
        with open(path) as f:
            rows = [r for r in csv.DictReader(l for l in f if not l.startswith("#"))
                    if r["valid"] == "1"][60:]
        if not rows:
            continue
        errors = [float(r["error_m"]) for r in rows]
        rmse = math.sqrt(sum(e * e for e in errors) / len(errors))
        big = [float(r["truth_nats"]) - float(r["estimate_nats"]) for r in rows
               if float(r["error_m"]) > args.error_cm / 100
               and not math.isnan(float(r["truth_nats"]))]
        equal = sum(1 for d in big if abs(d) < args.nats)
        truth = sum(1 for d in big if d >= args.nats)
        estimate = sum(1 for d in big if d <= -args.nats)
        spread = statistics.median(float(r["sigma_m"]) for r in rows)
        within = sum(1 for r in rows if float(r["error_m"]) < 3 * float(r["sigma_m"])) / len(rows)
        print(f"{seed_of(path):4d} {rmse * 100:8.1f} {len(big):15d} {equal:6d} {truth:13d} "
              f"{estimate:16d} {sum(big) / len(big) if big else 0.0:25.2f} {spread * 100:10.1f} "
              f"{within * 100:18.0f}")
        for k, v in enumerate((len(big), equal, truth, estimate)):
            totals[k] += v
    n = max(totals[0], 1)
    print(f"all: {totals[0]} frames > {args.error_cm:g} cm: equal {100 * totals[1] / n:.0f}%, "
          f"truth better {100 * totals[2] / n:.0f}%, estimate better {100 * totals[3] / n:.0f}%")
    return 0


if __name__ == "__main__":
    sys.exit(main())
