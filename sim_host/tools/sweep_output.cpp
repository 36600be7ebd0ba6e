// harmoloc-sweep's outputs: sweep.json's records and index.html with its strip plots.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "harmoloc/sim_host/svg.hpp"
#include "harmoloc/sim_host/svg_plot.hpp"
#include "harmoloc/sim_host/svg_ticks.hpp"
#include "sweep_parts.hpp"

namespace svg = harmoloc::sim_host::svg;

namespace sweep_detail {

nlohmann::json to_json(const SceneResult& r) {
  nlohmann::json j;
  j["seed"] = r.seed;
  j["scene"] = r.summary;
  if (!r.error.empty()) j["error"] = r.error;
  j["train_ms"] = r.train_ms;
  j["train_frames"] = r.train_frames;
  j["placement_rmse_m"] = r.placement_rmse_m;
  j["placement_heading_rmse_deg"] = r.placement_heading_rmse_deg;
  j["floor_placement_rmse_m"] = r.floor_placement_rmse_m;
  j["floor_placement_max_m"] = r.floor_placement_max_m;
  j["floor_placement_heading_rmse_deg"] = r.floor_placement_heading_rmse_deg;
  j["cv_rmse_x_m"] = r.cv_rmse_x_m;
  j["pass_heading_spread_rad"] = r.pass_heading_spread_rad;
  j["cv_rmse_y_m"] = r.cv_rmse_y_m;
  j["column_weight"] = r.column_weight;
  j["column_gain_c2"] = r.column_gain_c2;
  j["column_gain_c4"] = r.column_gain_c4;
  j["column_gain_observations"] = r.column_gain_observations;
  j["boards_used"] = r.boards_used;
  j["bearing_boards_placed"] = r.bearing_boards_placed;
  j["board_place_median_m"] = r.board_place_median_m;
  j["board_place_max_m"] = r.board_place_max_m;
  j["bearing_residual_deg"] = r.bearing_residual_deg;
  j["bearing_half_fov_deg"] = r.bearing_half_fov_deg;
  j["bearings_ms"] = r.bearings_ms;
  j["fix_mse_x_m2"] = r.fix_mse_x_m2;
  j["fix_mse_y_m2"] = r.fix_mse_y_m2;
  j["fix_known_fraction"] = r.fix_known_fraction;
  j["no_board_fraction"] = r.no_board_fraction;
  j["fix_known_mse_x_m2"] = r.fix_known_mse_x_m2;
  j["fix_known_mse_y_m2"] = r.fix_known_mse_y_m2;
  j["first_fix_s"] = r.first_fix_s;
  j["startup_s"] = r.startup_s;
  j["converge_s"] = r.converge_s;
  j["fused_rmse_m"] = r.fused_rmse_m;
  j["fused_heading_rmse_deg"] = r.fused_heading_rmse_deg;
  j["fused_max_m"] = r.fused_max_m;
  j["particles_mean"] = r.particles_mean;
  j["kidnaps"] = r.kidnaps;
  j["kidnaps_detected"] = r.kidnaps_detected;
  j["kidnaps_recovered_1s"] = r.kidnaps_recovered_1s;
  j["kidnap_mean_recovery_s"] = r.kidnap_mean_recovery_s;
  j["kidnap_misses_t_s"] = r.kidnap_misses_t_s;
  j["dynamic_max_m"] = r.dynamic_max_m;
  j["dynamic_rmse_m"] = r.dynamic_rmse_m;
  j["long_minutes"] = r.long_minutes;
  j["long_false_alarms"] = r.long_false_alarms;
  j["long_max_m"] = r.long_max_m;
  j["long_rmse_m"] = r.long_rmse_m;
  if (!r.floor_error.empty()) j["floor_error"] = r.floor_error;
  if (!r.floor_summary.empty()) j["floor_summary"] = r.floor_summary;
  j["floor_train_frames"] = r.floor_train_frames;
  j["floor_train_ms"] = r.floor_train_ms;
  j["floor_cv_rmse_x_m"] = r.floor_cv_rmse_x_m;
  j["floor_pass_heading_spread_rad"] = r.floor_pass_heading_spread_rad;
  j["floor_heading_ridge"] = r.floor_heading_ridge;
  j["floor_geometry_boards"] = r.floor_geometry_boards;
  j["floor_projected_boards"] = r.floor_projected_boards;
  j["floor_geometry_candidates"] = r.floor_geometry_candidates;
  j["floor_geometry_board_error_median_m"] = r.floor_geometry_board_error_median_m;
  j["floor_geometry_board_error_max_m"] = r.floor_geometry_board_error_max_m;
  j["floor_geometry_fov_error_deg"] = r.floor_geometry_fov_error_deg;
  j["floor_geometry_pitch_error_deg"] = r.floor_geometry_pitch_error_deg;
  j["floor_geometry_forward_error_m"] = r.floor_geometry_forward_error_m;
  j["floor_heading_rounds"] = r.floor_heading_rounds;
  j["floor_heading_offset_rms_deg"] = r.floor_heading_offset_rms_deg;
  j["floor_law_from_camera"] = r.floor_law_from_camera;
  j["floor_law_axis_deg"] = r.floor_law_axis_deg;
  j["floor_heading_bandwidth_m"] = r.floor_heading_bandwidth_m;
  j["floor_covered_heading_fraction"] = r.floor_covered_heading_fraction;
  j["floor_validation_rmse"] = r.floor_validation_rmse;
  j["floor_mean_validation_rmse"] = r.floor_mean_validation_rmse;
  j["floor_cv_rmse_y_m"] = r.floor_cv_rmse_y_m;
  j["floor_roam_s"] = r.floor_roam_s;
  j["floor_nearby_draws"] = r.floor_nearby_draws;
  j["floor_fix_mse_x_m2"] = r.floor_fix_mse_x_m2;
  j["floor_fix_mse_y_m2"] = r.floor_fix_mse_y_m2;
  j["floor_rmse_m"] = r.floor_rmse_m;
  j["floor_heading_rmse_deg"] = r.floor_heading_rmse_deg;
  j["floor_max_m"] = r.floor_max_m;
  j["floor_nominal_over_10cm"] = r.floor_nominal_over_10cm;
  j["floor_vouched_over_10cm"] = r.floor_vouched_over_10cm;
  j["floor_nominal_share"] = r.floor_nominal_share;
  j["floor_particles_mean"] = r.floor_particles_mean;
  j["floor_kidnaps"] = r.floor_kidnaps;
  j["floor_kidnaps_recovered_2s"] = r.floor_kidnaps_recovered_2s;
  j["floor_kidnap_nominal_over_10cm"] = r.floor_kidnap_nominal_over_10cm;
  j["floor_kidnap_vouched_over_10cm"] = r.floor_kidnap_vouched_over_10cm;
  j["seconds"] = r.seconds;
  return j;
}

std::string fmt(double v, int decimals) {
  if (v < 0.0 || !std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

namespace {

// A strip plot: one dot per scene on a horizontal axis, the median marked, the targets dashed,
// the worst scene labelled by seed; the default scene as a ring. Hover a dot for its seed.
std::string strip_svg(const Figure& f, const std::vector<SceneResult>& results,
                      const SceneResult* reference) {
  const Distribution d = distribution(results, f);
  std::vector<std::pair<double, std::uint64_t>> v;
  for (const SceneResult& r : results) {
    const double x = r.error.empty() ? f.value(r) : -1.0;
    if (x >= 0.0 && std::isfinite(x)) v.emplace_back(x, r.seed);
  }
  const double ref = reference != nullptr ? f.value(*reference) : -1.0;
  double hi = 0.0;
  for (const auto& p : v) hi = std::max(hi, p.first);
  hi = std::max({hi, f.target_worst, f.target_median, ref});
  if (f.unit == "%") hi = 100.0;
  if (!(hi > 0.0) || !std::isfinite(hi)) hi = 1.0;
  // The axis from 0 to a whole number of round steps.
  const double step = svg::nice_step(hi, 4);
  hi = std::ceil(hi / step - 1e-9) * step;
  const double width = 640.0;
  const svg::Area area{20.0, 22.0, width - 40.0, 38.0};
  const svg::Scale sx{0.0, hi, area.left, area.right()};
  constexpr const char* kDot = "#0066cc";
  constexpr const char* kWorst = "#cc0000";
  svg::Canvas c(width, 92.0);
  c.text(area.left, 14.0, f.title + (f.unit.empty() ? "" : " (" + f.unit + ")"), "start", 11.0,
         svg::kTextColour, " font-weight=\"bold\"");
  c.line(area.left, area.bottom(), area.right(), area.bottom(), "#888888", 1.0);
  for (const svg::Tick& t : svg::make_ticks(sx, step)) {
    c.line(t.px, area.bottom(), t.px, area.bottom() + 4.0, "#888888", 1.0);
    c.text(t.px, area.bottom() + 16.0, t.label, "middle", 11.0, svg::kMutedColour);
  }
  const auto vline = [&](double x, const char* colour, const char* label, bool dashed) {
    c.line(sx(x), area.top, sx(x), area.bottom(), colour, 1.0,
           dashed ? " stroke-dasharray=\"4,3\"" : "");
    // The label right of the line, or left of it where it would run off the plot.
    const bool fits = sx(x) + 3.0 + svg::text_width(label, 11.0) <= width;
    c.text(fits ? sx(x) + 3.0 : sx(x) - 3.0, area.top + 8.0, label, fits ? "start" : "end", 11.0,
           colour);
  };
  if (f.target_worst >= 0.0) vline(f.target_worst, kWorst, "target (worst)", true);
  if (f.target_median > 0.0) vline(f.target_median, "#ee8800", "target (median)", true);
  if (d.n > 0) vline(d.median, kDot, "median", false);
  const auto with_tooltip = [&c](const std::string& tip, const auto& draw) {
    c.raw("<g><title>" + svg::escape(tip) + "</title>\n");
    draw();
    c.raw("</g>\n");
  };
  std::size_t i = 0;
  for (const auto& [x, seed] : v) {
    const double jitter = static_cast<double>((i++ * 7) % 11) - 5.0;
    with_tooltip("seed " + std::to_string(seed) + ": " + fmt(x), [&] {
      c.circle(sx(x), area.bottom() - 12.0 + jitter, 3.0, kDot, " fill-opacity=\"0.6\"");
    });
  }
  if (d.n > 0 && !d.worst_seeds.empty()) {
    c.text(std::min(sx(d.worst), width - 60.0), area.bottom() - 22.0,
           "seed " + std::to_string(d.worst_seeds.front()), "start", 11.0, kWorst);
  }
  if (ref >= 0.0) {
    with_tooltip("default scene: " + fmt(ref), [&] {
      c.circle(sx(ref), area.bottom() - 12.0, 5.0, "none",
               " stroke=\"#008800\" stroke-width=\"2\"");
    });
  }
  return svg::inline_svg(c.finish());
}

}  // namespace

void write_html(const std::string& path, const std::vector<SceneResult>& results,
                const SceneResult* reference, const std::string& command) {
  std::ofstream o(path);
  o << "<!doctype html><html><head><meta charset='utf-8'><title>harmoloc sweep</title>"
    << "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto}"
    << "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 6px;"
    << "text-align:right}th{background:#eee}td.l{text-align:left}.bad{color:#c00;"
    << "font-weight:bold}</style></head><body>";
  o << "<h1>harmoloc sweep over random scenes</h1><p>" << svg::escape(command) << "</p>";
  std::size_t failed = 0;
  bool floor = false;
  for (const SceneResult& r : results) {
    failed += r.error.empty() && r.floor_error.empty() ? 0 : 1;
    floor = floor || r.floor_rmse_m >= 0.0 || !r.floor_error.empty();
  }
  o << "<p>" << results.size() << " scenes, " << failed
    << " failed. Each dot is a scene; the green ring is the project's own default scene "
       "(desk-shuttle). Hover a dot for its seed.</p>";
  o << "<table><tr><th class='l'>figure</th><th>scenes</th><th>median</th><th>90th pct</th>"
    << "<th>worst</th><th class='l'>worst seeds</th><th>default scene</th><th>target</th></tr>";
  for (const Figure& f : figures()) {
    const Distribution d = distribution(results, f);
    std::string seeds;
    for (std::uint64_t s : d.worst_seeds) seeds += (seeds.empty() ? "" : ", ") + std::to_string(s);
    std::string target;
    if (f.target_median >= 0.0) target += "median &le; " + fmt(f.target_median, 1);
    if (f.target_worst >= 0.0)
      target += std::string(target.empty() ? "" : ", ") + "worst &le; " + fmt(f.target_worst, 1);
    const bool bad = (f.target_worst >= 0.0 && d.n > 0 && d.worst > f.target_worst) ||
                     (f.target_median >= 0.0 && d.n > 0 && d.median > f.target_median);
    o << "<tr><td class='l'>" << svg::escape(f.title + (f.unit.empty() ? "" : " (" + f.unit + ")"))
      << "</td><td>" << d.n << "</td><td>" << fmt(d.median) << "</td><td>" << fmt(d.p90)
      << "</td><td" << (bad ? " class='bad'" : "") << ">" << fmt(d.worst) << "</td><td class='l'>"
      << seeds << "</td><td>" << (reference != nullptr ? fmt(f.value(*reference)) : "-")
      << "</td><td class='l'>" << target << "</td></tr>";
  }
  o << "</table>";
  for (const Figure& f : figures()) o << "<div>" << strip_svg(f, results, reference) << "</div>";
  o << "<h2>Scenes</h2><table><tr><th>seed</th><th class='l'>scene</th><th>fix MSE x/y (cm^2)</th>"
    << "<th>fused RMSE (cm)</th><th>start-up (s)</th><th>kidnaps in 1 s</th>"
    << "<th>false alarms</th><th>dynamic max (cm)</th>"
    << (floor ? "<th>floor RMSE (cm)</th><th>floor heading (deg)</th>" : "")
    << "<th class='l'>error</th></tr>";
  for (const SceneResult& r : results) {
    o << "<tr><td>" << r.seed << "</td><td class='l'>" << svg::escape(r.summary) << "</td><td>"
      << fmt(cm2(r.fix_mse_x_m2), 1) << " / " << fmt(cm2(r.fix_mse_y_m2), 1) << "</td><td>"
      << fmt(cm(r.fused_rmse_m)) << "</td><td>" << fmt(r.startup_s) << "</td><td>"
      << r.kidnaps_recovered_1s << "/" << r.kidnaps << "</td><td>" << r.long_false_alarms
      << "</td><td>" << fmt(cm(r.dynamic_max_m), 1) << "</td>";
    if (floor)
      o << "<td>" << fmt(cm(r.floor_rmse_m)) << "</td><td>" << fmt(r.floor_heading_rmse_deg)
        << "</td>";
    o << "<td class='l'>"
      << svg::escape(r.error + (r.floor_error.empty() ? "" : " floor: " + r.floor_error))
      << "</td></tr>";
  }
  o << "</table></body></html>\n";
}

}  // namespace sweep_detail
