#!/usr/bin/env python3
"""Checks the trace of a floor's kidnap roam run with the floor search on (kidnap.floor_search,
docs/filter.md, "The floor search"): the search gave the kidnap test its evidence pose, found the
robot within 10 cm of its new place after a kidnap, and a kidnap was confirmed from it. The
figures themselves are the sweep's (docs/sweep.md); this only shows the path works end to end."""
import csv
import math
import sys


def main():
    if len(sys.argv) != 2:
        print("usage: check_floor_search_trace.py SEED-N-floor-kidnap.csv", file=sys.stderr)
        return 2
    path = sys.argv[1]
    with open(path) as f:
        lines = f.readlines()
    kidnaps = [float(l.split()[3]) for l in lines if l.startswith("# kidnap at")]
    rows = list(csv.DictReader(l for l in lines if not l.startswith("#")))
    problems = []
    if not kidnaps:
        problems.append("no kidnap in the run")
    evidence = [r for r in rows if r["evidence_known"] == "1"]
    if not evidence:
        problems.append("the floor search gave no evidence pose in any frame")
    found = 0
    for t in kidnaps:
        for r in rows:
            if t <= float(r["t_s"]) <= t + 2.0 and r["evidence_known"] == "1" and math.hypot(
                    float(r["evidence_x_m"]) - float(r["truth_x_m"]),
                    float(r["evidence_y_m"]) - float(r["truth_y_m"])) < 0.10:
                found += 1
                break
    if found == 0:
        problems.append("after no kidnap did the search's pose come within 10 cm of the robot")
    confirmed = sum(1 for r in rows if r["verdict"] == "2")
    if confirmed == 0:
        problems.append("no kidnap confirmed")
    for p in problems:
        print("check_floor_search_trace: " + p)
    print(f"check_floor_search_trace: {len(kidnaps)} kidnaps, evidence in {len(evidence)} of "
          f"{len(rows)} frames, the robot found within 10 cm after {found}, {confirmed} confirmed")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
