#!/usr/bin/env python3
"""Checks a floor sweep's sweep.json (harmoloc-sweep --parts floor, issue 20): every scene's
coverage run trained into a floor map (its passes 10 degrees or more apart in heading, so that
the firmware drops the route terms), its visibility tables taken from the fitted geometry on some
board, and its roams replayed and scored. No accuracy bound yet (docs/sweep.md, "Floor runs").
The nearby pose test's draws must be recorded; that it draws is sweep.floor_search's check
(check_floor_search_trace.py --sweep): seed 5's roam, tracked within 2 cm since the harmonic fix
stopped weighing the particles on a floor map, gives it no place to draw at.
"""
import json
import sys

FIGURES = ["floor_rmse_m", "floor_heading_rmse_deg", "floor_max_m", "floor_nominal_over_10cm",
           "floor_vouched_over_10cm", "floor_nominal_share", "floor_fix_mse_x_m2",
           "floor_fix_mse_y_m2", "floor_cv_rmse_x_m", "floor_cv_rmse_y_m"]


def main():
    if len(sys.argv) != 2:
        print("usage: check_floor_sweep.py SWEEP_JSON", file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        d = json.load(f)
    problems = []
    results = d.get("results", [])
    if not results:
        problems.append("no scenes in the sweep")
    for r in results:
        seed = r["seed"]
        if r.get("floor_error") or r.get("error"):
            problems.append(f"seed {seed}: failed: {r.get('floor_error') or r.get('error')}")
            continue
        for key in FIGURES:
            if not r.get(key, -1.0) >= 0.0:
                problems.append(f"seed {seed}: {key} not measured")
        turned_deg = r.get("floor_pass_heading_spread_rad", -1.0) * 180.0 / 3.141592653589793
        if not turned_deg >= 10.0:
            problems.append(f"seed {seed}: the coverage run's passes {turned_deg:.1f} deg apart: "
                            "not a floor map")
        if r.get("floor_train_frames", 0) < 1000:
            problems.append(f"seed {seed}: coverage run of {r.get('floor_train_frames', 0)} frames")
        if not r.get("floor_roam_s", 0.0) > 10.0:
            problems.append(f"seed {seed}: roams of {r.get('floor_roam_s', 0.0)} s")
        if r.get("floor_kidnaps", 0) < 1:
            problems.append(f"seed {seed}: no kidnap in the floor's kidnap roam")
        # KLD-sampling is on by default on a floor map (filter.kld = "auto"): the roams' cloud,
        # once converged, holds fewer than the 1024 particles of the capacity and never fewer
        # than kld_min_particles (256); a fixed count would give exactly 1024.
        particles = r.get("floor_particles_mean", -1.0)
        if not 256.0 <= particles < 1000.0:
            problems.append(f"seed {seed}: {particles} particles a cycle in the roams: "
                            "not the adaptive count of a floor map")
        # The floor map's visibility tables come from the fitted camera and boards by default
        # (the sweep gives the scene's camera height): some board must have taken them.
        if d.get("options", {}).get("visibility_from_geometry", True) and \
                not r.get("floor_geometry_boards", 0) >= 1:
            problems.append(f"seed {seed}: no board took the geometry's visibility tables "
                            f"({r.get('floor_geometry_candidates', 0)} fitted)")
        # The fitted geometry against the scene's truth: recorded wherever boards were fitted,
        # and near the truth (a board matched to the wrong scene board, or a fit gone astray,
        # lands metres off; the fits of random floors are off by centimetres to decimetres).
        if r.get("floor_geometry_candidates", 0) >= 1:
            err = r.get("floor_geometry_board_error_median_m")
            if err is None or not 0.0 <= err < 0.5:
                problems.append(f"seed {seed}: fitted boards' median centre error {err} m "
                                "(not recorded, or 50 cm or more off the scene's)")
            for key in ("floor_geometry_fov_error_deg", "floor_geometry_pitch_error_deg",
                        "floor_geometry_forward_error_m"):
                if not isinstance(r.get(key), (int, float)):
                    problems.append(f"seed {seed}: {key} not recorded")
            # With the fit, the floor map's column-to-angle law is the fitted camera's (unless the
            # sweep was asked to keep the frames' law), and its axis a few degrees at most off
            # the frame's centre column.
            if not d.get("options", {}).get("law_from_frames", False):
                axis = r.get("floor_law_axis_deg")
                if not r.get("floor_law_from_camera", False):
                    problems.append(f"seed {seed}: the law did not come from the fitted camera")
                elif not isinstance(axis, (int, float)) or not abs(axis) < 10.0:
                    problems.append(f"seed {seed}: the fitted camera's axis at {axis} deg")
        # Where the trainer placed the coverage run's frames, against the truth: recorded, the
        # RMSE no more than the largest, and within centimetres (labels and odometry place them
        # to millimetres on random floors; a frame matched to the wrong label lands far off).
        rmse, worst = r.get("floor_placement_rmse_m"), r.get("floor_placement_max_m")
        if not isinstance(rmse, (int, float)) or not isinstance(worst, (int, float)) or \
                not 0.0 <= rmse <= worst < 0.1 or \
                not r.get("floor_placement_heading_rmse_deg", -1.0) >= 0.0:
            problems.append(f"seed {seed}: the coverage run's placement {rmse} m RMSE, {worst} m "
                            "at most (not recorded, or 10 cm or more off)")
        if r.get("fused_rmse_m", -1.0) >= 0.0:
            problems.append(f"seed {seed}: a route part ran although only the floor was asked for")
    # The nearby pose test (filter.nearby_test, on by default) runs on every floor map with
    # bearings; its draws are recorded (a floor tracked within centimetres may give it none).
    if results and not any("floor_nearby_draws" in r for r in results):
        problems.append("floor_nearby_draws not recorded")
    for p in problems:
        print("check_floor_sweep: " + p)
    print(f"check_floor_sweep: {len(results)} scenes, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
