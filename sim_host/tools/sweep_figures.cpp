// harmoloc-sweep's figures: how each is read off a scene, and their distributions over scenes.
#include <algorithm>
#include <cmath>

#include "sweep_parts.hpp"

namespace sweep_detail {

std::vector<Figure> figures() {
  return {
      {"fix_mse_x", "harmonic localizer alone, MSE x", "cm^2",
       [](const SceneResult& r) { return cm2(r.fix_mse_x_m2); }, 10.0, 25.0},
      {"fix_mse_y", "harmonic localizer alone, MSE y", "cm^2",
       [](const SceneResult& r) { return cm2(r.fix_mse_y_m2); }, 10.0, 25.0},
      {"fix_known", "fixes flagged a known place", "%",
       [](const SceneResult& r) {
         return r.fix_known_fraction < 0.0 ? -1.0 : 100.0 * r.fix_known_fraction;
       },
       -1.0, -1.0, true},
      {"no_board", "frames without a board of the localizer's in view (no fix)", "%",
       [](const SceneResult& r) {
         return r.no_board_fraction < 0.0 ? -1.0 : 100.0 * r.no_board_fraction;
       }},
      {"fused_rmse", "fused position RMSE (after first fix + 2 s)", "cm",
       [](const SceneResult& r) { return cm(r.fused_rmse_m); }, 2.0, 4.0},
      {"fused_heading", "fused heading RMSE", "deg",
       [](const SceneResult& r) { return r.fused_heading_rmse_deg; }},
      {"startup", "start-up: from the first fix until under 5 cm (held 1 s)", "s",
       [](const SceneResult& r) { return r.startup_s; }, -1.0, 2.0},
      {"converge", "time from the first fix until under 5 cm for good", "s",
       [](const SceneResult& r) { return r.converge_s; }},
      {"fused_max", "fused max error after first fix + 2 s", "cm",
       [](const SceneResult& r) { return cm(r.fused_max_m); }, -1.0, 10.0},
      {"particles", "particles per cycle, mean (nominal run)", "",
       [](const SceneResult& r) { return r.particles_mean; }},
      {"kidnap_recovered", "kidnaps back under 10 cm within 1 s", "%",
       [](const SceneResult& r) {
         return r.kidnaps == 0 ? -1.0
                               : 100.0 * static_cast<double>(r.kidnaps_recovered_1s) /
                                     static_cast<double>(r.kidnaps);
       },
       -1.0, -1.0, true},
      {"false_alarms", "false kidnap alarms per 10 minutes", "",
       [](const SceneResult& r) {
         return r.long_minutes <= 0.0
                    ? -1.0
                    : static_cast<double>(r.long_false_alarms) * 10.0 / r.long_minutes;
       },
       -1.0, 0.0},
      {"dynamic_max", "dynamic run (person, moved board): max error", "cm",
       [](const SceneResult& r) { return cm(r.dynamic_max_m); }, -1.0, 10.0},
      {"long_max", "long nominal run: max error", "cm",
       [](const SceneResult& r) { return cm(r.long_max_m); }, -1.0, 10.0},
      {"placement", "training frames placed by odometry, RMSE", "mm",
       [](const SceneResult& r) {
         return r.placement_rmse_m < 0.0 ? -1.0 : 1000.0 * r.placement_rmse_m;
       }},
      {"train_ms", "training time (area log in memory)", "ms",
       [](const SceneResult& r) { return r.train_ms; }},
      {"board_place", "boards placed from centroid columns, median error (not used yet)", "cm",
       [](const SceneResult& r) { return cm(r.board_place_median_m); }},
      {"board_place_max", "boards placed from centroid columns, worst board (not used yet)", "cm",
       [](const SceneResult& r) { return cm(r.board_place_max_m); }},
      {"bearing_residual", "bearing residual of the placed boards, RMS", "deg",
       [](const SceneResult& r) { return r.bearing_residual_deg; }},
      // Issue 20: the floor runs (--parts floor) and their targets.
      {"floor_rmse", "floor roams: fused position RMSE (after first fix + 2 s)", "cm",
       [](const SceneResult& r) { return cm(r.floor_rmse_m); }, 3.0, 6.0},
      {"floor_heading", "floor roams: fused heading RMSE", "deg",
       [](const SceneResult& r) { return r.floor_heading_rmse_deg; }, 2.0, -1.0},
      {"floor_max", "floor roams: max error", "cm",
       [](const SceneResult& r) { return cm(r.floor_max_m); }},
      {"floor_nominal_bad", "floor roams: cycles nominal with error > 10 cm", "%",
       [](const SceneResult& r) {
         return r.floor_nominal_over_10cm < 0.0 ? -1.0 : 100.0 * r.floor_nominal_over_10cm;
       },
       -1.0, 0.0},
      {"floor_vouched_bad", "floor roams: cycles nominal, quality > 0, error > 10 cm", "%",
       [](const SceneResult& r) {
         return r.floor_vouched_over_10cm < 0.0 ? -1.0 : 100.0 * r.floor_vouched_over_10cm;
       },
       -1.0, 0.0},
      {"floor_nominal", "floor roams: cycles reported nominal", "%",
       [](const SceneResult& r) {
         return r.floor_nominal_share < 0.0 ? -1.0 : 100.0 * r.floor_nominal_share;
       }},
      {"floor_kidnaps", "floor roams: kidnaps back under 10 cm within 2 s", "%",
       [](const SceneResult& r) {
         return r.floor_kidnaps == 0 ? -1.0
                                     : 100.0 * static_cast<double>(r.floor_kidnaps_recovered_2s) /
                                           static_cast<double>(r.floor_kidnaps);
       },
       -1.0, -1.0, true},
      {"floor_kidnap_nominal_bad", "floor roams with kidnaps: cycles nominal with error > 10 cm",
       "%",
       [](const SceneResult& r) {
         return r.floor_kidnap_nominal_over_10cm < 0.0 ? -1.0
                                                       : 100.0 * r.floor_kidnap_nominal_over_10cm;
       }},
      {"floor_kidnap_vouched_bad",
       "floor roams with kidnaps: cycles nominal, quality > 0, error > 10 cm", "%",
       [](const SceneResult& r) {
         return r.floor_kidnap_vouched_over_10cm < 0.0 ? -1.0
                                                       : 100.0 * r.floor_kidnap_vouched_over_10cm;
       }},
      {"floor_fix_mse_x", "floor roams: harmonic localizer alone, MSE x", "cm^2",
       [](const SceneResult& r) { return cm2(r.floor_fix_mse_x_m2); }},
      {"floor_fix_mse_y", "floor roams: harmonic localizer alone, MSE y", "cm^2",
       [](const SceneResult& r) { return cm2(r.floor_fix_mse_y_m2); }},
      // The camera and boards fitted to the coverage run against the scene's (the trainer does
      // not see the truth; the sweep does).
      {"floor_geometry_board", "floor geometry fit: board centre error, median board", "cm",
       [](const SceneResult& r) { return cm(r.floor_geometry_board_error_median_m); }},
      {"floor_geometry_board_max", "floor geometry fit: board centre error, worst board", "cm",
       [](const SceneResult& r) { return cm(r.floor_geometry_board_error_max_m); }},
      {"floor_geometry_fov", "floor geometry fit: field of view error (absolute)", "deg",
       [](const SceneResult& r) { return std::fabs(r.floor_geometry_fov_error_deg); }},
      {"floor_geometry_pitch", "floor geometry fit: pitch error (absolute)", "deg",
       [](const SceneResult& r) { return std::fabs(r.floor_geometry_pitch_error_deg); }},
      {"floor_geometry_forward", "floor geometry fit: camera offset error (absolute)", "cm",
       [](const SceneResult& r) { return 100.0 * std::fabs(r.floor_geometry_forward_error_m); }},
  };
}

Totals totals_of(const std::vector<SceneResult>& results) {
  Totals t;
  for (const SceneResult& r : results) {
    t.kidnaps += r.kidnaps;
    t.recovered += r.kidnaps_recovered_1s;
    t.floor_kidnaps += r.floor_kidnaps;
    t.floor_recovered += r.floor_kidnaps_recovered_2s;
    t.alarms += r.long_false_alarms;
    t.minutes += r.long_minutes;
    t.failed += r.error.empty() && r.floor_error.empty() ? 0 : 1;
  }
  return t;
}

Distribution distribution(const std::vector<SceneResult>& results, const Figure& f) {
  std::vector<std::pair<double, std::uint64_t>> v;
  for (const SceneResult& r : results) {
    if (!r.error.empty()) continue;
    const double x = f.value(r);
    if (x >= 0.0 && std::isfinite(x)) v.emplace_back(x, r.seed);
  }
  Distribution d;
  d.n = v.size();
  if (v.empty()) return d;
  // "Worse" is larger, or smaller for higher-is-better figures.
  std::sort(v.begin(), v.end(), [&](const auto& a, const auto& b) {
    return f.higher_is_better ? a.first > b.first : a.first < b.first;
  });
  const auto at = [&](double q) {
    const double pos = q * static_cast<double>(v.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(pos));
    const auto hi = std::min(v.size() - 1, lo + 1);
    return v[lo].first + (pos - static_cast<double>(lo)) * (v[hi].first - v[lo].first);
  };
  d.median = at(0.5);
  d.p90 = at(0.9);
  d.worst = v.back().first;
  for (std::size_t i = 0; i < 3 && i < v.size(); ++i)
    d.worst_seeds.push_back(v[v.size() - 1 - i].second);
  return d;
}

}  // namespace sweep_detail
