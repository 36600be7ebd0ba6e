#!/usr/bin/env python3
"""Checks the trace of a floor's kidnap roam run with the floor search on (kidnap.floor_search,
docs/filter.md, "The floor search"): the search gave the kidnap test its evidence pose, found the
robot within 10 cm of its new place after a kidnap, and a kidnap was confirmed from it; and the
boards' fit columns (truth_nats, estimate_nats) hold fits, the truth's the better just after a
kidnap; every row has the header's columns, and the distance off the lanes (truth_lane_m) is
known, and how far each weighed frame leaves the position open (frame_sigma_m) is written with
the fits, and the search's heading and the nearby pose test's sum, kind and draws are written. The
figures themselves are the sweep's (docs/sweep.md); this only shows the path works
end to end.

With --sweep it also asks that the nearby pose test drew particles on some floor's roams
(floor_nearby_draws in its sweep.json; random floors 2 and 6 give it 6 and 2 draws), and with
--min-recovered that many of the roam's kidnaps to have come back under 10 cm within 2 s (the
sweep's own count, floor_kidnaps_recovered_2s)."""
import argparse
import csv
import json
import math
import sys


def main():
    parser = argparse.ArgumentParser(
        description="Checks the trace of a floor's kidnap roam run with the floor search on.")
    parser.add_argument("trace", help="the kidnap roam's trace, SEED-N-floor-kidnap.csv")
    parser.add_argument("--sweep", help="the sweep's sweep.json (for --min-recovered)")
    parser.add_argument("--min-recovered", type=int, default=0,
                        help="kidnaps that must be back under 10 cm within 2 s (default 0)")
    args = parser.parse_args()
    if args.min_recovered > 0 and not args.sweep:
        parser.error("--min-recovered needs --sweep")
    path = args.trace
    with open(path) as f:
        lines = f.readlines()
    kidnaps = [float(l.split()[3]) for l in lines if l.startswith("# kidnap at")]
    bounds = [float(l.split()[3]) for l in lines if l.startswith("# fit bound")]
    rows = list(csv.DictReader(l for l in lines if not l.startswith("#")))
    problems = []
    # Every row as many fields as the header names: a column written without its value (or a
    # value without its column) shifts every column after it.
    # Nothing after it can be read by name, so the check stops there.
    if any(None in r or None in r.values() for r in rows):
        print("check_floor_search_trace: a row whose fields do not match the header's columns")
        return 1
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
    # The boards' fit at the truth and at the estimate (nats, at most ln(1 + c) a term; the
    # replay writes the bound for its map and config), written on the cycles that weighed the
    # boards (nan on the others): while the estimate is still at the old place just after a
    # kidnap, the frame must fit the truth better.
    bound = bounds[0] if bounds else float("nan")
    if not bounds:
        problems.append("no '# fit bound' line: the replay computed no fits")
    fitted = [r for r in rows if not math.isnan(float(r["truth_nats"]))]
    if len(fitted) * 2 < len(rows):
        problems.append(f"fits in only {len(fitted)} of {len(rows)} frames")
    # The first frame seeds the filter without weighing the boards: no fit is written for it
    # (there is no frame's observation yet to fit).
    if rows and not math.isnan(float(rows[0]["truth_nats"])):
        problems.append("a fit written for the first frame, which weighed no boards")
    if any(math.isnan(float(r["estimate_nats"])) for r in fitted):
        problems.append("a fit at the truth without one at the estimate")
    if any(not (float(r["truth_nats"]) <= bound and float(r["estimate_nats"]) <= bound)
           for r in fitted):
        problems.append(f"a fit above a perfect one ({bound} nats)")
    away = [r for r in fitted if float(r["error_m"]) > 0.5 and r["valid"] == "1" and any(
        t <= float(r["t_s"]) <= t + 0.3 for t in kidnaps)]
    truth_better = sum(1 for r in away if float(r["truth_nats"]) > float(r["estimate_nats"]))
    if not away or 2 * truth_better <= len(away):
        problems.append(f"the truth fitted better than an estimate 0.5 m off in {truth_better} "
                        f"of {len(away)} frames just after a kidnap")
    # A fix leaves a cut board out only when it is a fix: a board of the localizer's was seen.
    if rows and "cut_board" not in rows[0]:
        problems.append("no cut_board column")
    elif any(r["cut_board"] not in ("0", "1") or (r["cut_board"] == "1" and r["board_seen"] != "1")
             for r in rows):
        problems.append("a cut_board entry that is not 0 or 1, or 1 on a frame without a fix")
    # The fix check's suspects: a mask of the scene's boards (the chi2_N columns).
    boards = sum(1 for k in rows[0] if k.startswith("chi2_")) if rows else 0
    if rows and "fix_suspects" not in rows[0]:
        problems.append("no fix_suspects column")
    elif any(not r["fix_suspects"].isdigit() or int(r["fix_suspects"]) >> boards for r in rows):
        problems.append(f"a fix_suspects entry that is not a mask of the {boards} boards")
    # The distance off the coverage run's lanes: known on a floor map, never negative, and the
    # kidnap roam goes anywhere on the floor, so it cannot hold on a lane throughout.
    if rows and "truth_lane_m" not in rows[0]:
        problems.append("no truth_lane_m column")
    elif rows:
        lanes = [float(r["truth_lane_m"]) for r in rows]
        if any(not (d >= 0.0) for d in lanes):
            problems.append("a truth_lane_m entry that is negative or not a number")
        elif max(lanes) <= 0.0:
            problems.append("truth_lane_m is 0 throughout the roam")
    # How far each weighed frame leaves the position open (frame_information): written with the
    # fits, a spread above 0 (inf where some direction is not fixed) and nan on the others.
    if rows and "frame_sigma_m" not in rows[0]:
        problems.append("no frame_sigma_m column")
    elif rows:
        spreads = [float(r["frame_sigma_m"]) for r in rows if not math.isnan(float(r["truth_nats"]))]
        if not spreads or any(not (s > 0.0) for s in spreads):
            problems.append("a frame with fits but no frame_sigma_m above 0")
        elif not any(math.isfinite(s) for s in spreads):
            problems.append("frame_sigma_m is infinite on every frame")
    # The search's own pose and fit, and the fit the search would find at the truth's place:
    # table fits, so at most the bound; the search's fit is written on the frames with fits
    # where it holds a pose (nan where it has none yet, or the frame gives no bearing).
    # The filter's own model at the truth, the search's pose and the estimate: log-likelihoods,
    # finite where written.
    wanted = ("search_x_m", "search_y_m", "search_nats", "truth_seen_nats", "truth_model_nats",
              "search_model_nats", "estimate_model_nats")
    missing = [c for c in wanted if rows and c not in rows[0]]
    if missing:
        problems.append("no column " + ", ".join(missing))
    elif rows:
        searched = [r for r in fitted if not math.isnan(float(r["search_nats"]))]
        if not searched:
            problems.append("the search's fit written on no frame")
        if any(not (float(r[c]) <= bound) for r in searched
               for c in ("search_nats", "truth_seen_nats") if not math.isnan(float(r[c]))):
            problems.append(f"a search fit above a perfect one ({bound} nats)")
        if any(math.isinf(float(r[c])) for r in fitted
               for c in ("truth_model_nats", "search_model_nats", "estimate_model_nats")):
            problems.append("a model log-likelihood that is not finite")
    # The boards in view and those of them giving a bearing: counts within the boards, the
    # bearings no more than the boards in view, some board in view on most frames with fits.
    counted = ("boards_in_view", "boards_with_bearing")
    missing = [c for c in counted if rows and c not in rows[0]]
    if missing:
        problems.append("no column " + ", ".join(missing))
    elif fitted:
        in_view = [int(r["boards_in_view"]) for r in fitted]
        bearings = [int(r["boards_with_bearing"]) for r in fitted]
        if any(not 0 <= v <= 8 for v in in_view) or any(b > v for b, v in zip(bearings, in_view)):
            problems.append("boards_in_view or boards_with_bearing out of range")
        if sum(1 for v in in_view if v > 0) < 0.5 * len(in_view):
            problems.append("no board in view on most frames with fits")
    # The search's heading, written with its pose; the nearby pose test's sum (nan when it holds
    # no alternative), whether the search's pose is weighed by the tables, and its draws so far
    # (never fewer than the frame before, and some on a roam with kidnaps).
    nearby = ("search_yaw_rad", "nearby_sum_nats", "nearby_by_tables", "nearby_draws")
    missing = [c for c in nearby if rows and c not in rows[0]]
    if missing:
        problems.append("no column " + ", ".join(missing))
    elif rows:
        if any(math.isnan(float(r["search_yaw_rad"])) != math.isnan(float(r["search_nats"]))
               for r in rows):
            problems.append("search_yaw_rad written where the search's fit is not, or not where it is")
        if any(r["nearby_by_tables"] not in ("0", "1") for r in rows):
            problems.append("nearby_by_tables not 0 or 1 on a floor")
        if any(r["nearby_by_tables"] == "1" and math.isnan(float(r["nearby_sum_nats"]))
               for r in rows):
            problems.append("the tables' alternative held with no sum")
        draws = [int(r["nearby_draws"]) for r in rows]
        if any(b < a for a, b in zip(draws, draws[1:])):
            problems.append("nearby_draws fell")
        if not any(r["nearby_by_tables"] == "1" for r in rows):
            problems.append("the tables never weighed the search's pose after a re-seed")
    confirmed = sum(1 for r in rows if r["verdict"] == "2")
    if confirmed == 0:
        problems.append("no kidnap confirmed")
    recovered = None
    if args.sweep:
        with open(args.sweep) as f:
            results = json.load(f)["results"]
        recovered = sum(r.get("floor_kidnaps_recovered_2s", 0) for r in results)
        total = sum(r.get("floor_kidnaps", 0) for r in results)
        if recovered < args.min_recovered:
            problems.append(f"{recovered} of {total} kidnaps back under 10 cm within 2 s, "
                            f"fewer than {args.min_recovered}")
        # The nearby pose test (filter.nearby_test, on by default) on the roams.
        if sum(r.get("floor_nearby_draws", 0) for r in results) == 0:
            problems.append("the nearby pose test drew on no floor's roam")
    for p in problems:
        print("check_floor_search_trace: " + p)
    print(f"check_floor_search_trace: {len(kidnaps)} kidnaps, evidence in {len(evidence)} of "
          f"{len(rows)} frames, the robot found within 10 cm after {found}, {confirmed} confirmed; "
          f"the truth fitted better in {truth_better} of {len(away)} frames 0.5 m off" +
          ("" if recovered is None else f"; {recovered} back within 2 s"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
