// The report's HTML page: self-contained (inline CSS, plots as relative <img>), so that the
// folder can be copied or mailed and opened anywhere without a server.
#include "harmoloc/sim_host/report.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "format.hpp"
#include "harmoloc/sim_host/svg.hpp"
#include "page_style.hpp"

namespace harmoloc::sim_host {

using report_text::budget;
using report_text::cell;
using report_text::format;
using report_text::seconds;
using svg::escape;

namespace {

void html_row(std::string& out, const std::string& label, const std::vector<std::string>& cells,
              const std::vector<bool>& over = {}) {
  out += "<tr><td>" + escape(label) + "</td>";
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const bool red = i < over.size() && over[i];
    out += red ? "<td class=\"over\">" : "<td>";
    out += escape(cells[i]) + "</td>";
  }
  out += "</tr>\n";
}

std::string rpe_cell(const RelativeErrors& r, double metres) {
  return r.pairs == 0 ? std::string("n/a") : cell(metres * 100.0, 2);
}

// Relative error (drift over 1 m and 1 s, evo_rpe's translation part) beside the absolute one.
void relative_error_table(std::string& out, const Report& report) {
  struct Column {
    std::string name;
    const RelativeErrors* m;
    const RelativeErrors* s;
    const TrajectoryErrors* absolute;
  };
  std::vector<Column> columns = {
      {"fused estimate", &report.rpe_1m, &report.rpe_1s, &report.estimate_all}};
  if (report.rpe_1m_converged && report.rpe_1s_converged && report.estimate_converged) {
    columns.push_back({"fused, after " + seconds(report.inputs.skip_initial_s),
                       &*report.rpe_1m_converged, &*report.rpe_1s_converged,
                       &*report.estimate_converged});
  }
  out += "<h2>Relative error (drift)</h2>\n<table class=\"rpe\">\n<tr><th></th>";
  for (const Column& c : columns) out += "<th>" + escape(c.name) + "</th>";
  out += "</tr>\n";
  const auto row = [&](const std::string& label, auto value) {
    std::vector<std::string> cells;
    for (const Column& c : columns) cells.push_back(value(c));
    html_row(out, label, cells);
  };
  row("absolute: RMSE position (cm)",
      [](const Column& c) { return cell(c.absolute->rmse_position_m * 100.0, 2); });
  for (const bool metres : {true, false}) {
    const std::string over = metres ? "RPE over 1 m" : "RPE over 1 s";
    const auto pick = [metres](const Column& c) { return metres ? c.m : c.s; };
    row(over + ": pairs", [&](const Column& c) { return std::to_string(pick(c)->pairs); });
    row(over + ": RMSE (cm)", [&](const Column& c) { return rpe_cell(*pick(c), pick(c)->rmse_m); });
    row(over + ": median (cm)",
        [&](const Column& c) { return rpe_cell(*pick(c), pick(c)->median_m); });
    row(over + ": max (cm)", [&](const Column& c) { return rpe_cell(*pick(c), pick(c)->max_m); });
  }
  out += "</table>\n<p class=\"note\">" +
         escape(
             "Relative Pose Error, translation part, as evo_rpe reports it with consecutive "
             "pairs: over 1 m of the estimate's path (evo_rpe --delta 1 --delta_unit m) and "
             "over 1 s (at a steady rate, evo's --delta_unit f with the frames of a second). A "
             "constant offset costs nothing here; drift does.") +
         "</p>\n";
}

// What the link recording adds: time in each health and how honest the claimed spread is.
void link_table(std::string& out, const Report& report) {
  const LinkLog& link = *report.link;
  out += "<h2>Health and spread (from the link)</h2>\n<table class=\"link\">\n";
  html_row(out, "poses on the link", {std::to_string(link.poses.size())});
  html_row(out, "health changes",
           {std::to_string(link.health.empty() ? 0 : link.health.size() - 1)});
  double total_s = 0.0;
  for (const HealthSpan& span : link.health) total_s += span.end_s - span.start_s;
  for (const firmware::Health h :
       {firmware::Health::kNominal, firmware::Health::kOdometryOnly, firmware::Health::kVisionOnly,
        firmware::Health::kInvalid, firmware::Health::kNotInitialized}) {
    double time_s = 0.0;
    for (const HealthSpan& span : link.health) {
      if (span.health == h) time_s += span.end_s - span.start_s;
    }
    if (time_s <= 0.0) continue;
    html_row(out, std::string("time ") + health_label(h),
             {format("%.1f s (%.1f%%)", time_s, total_s > 0.0 ? 100.0 * time_s / total_s : 0.0)},
             {h == firmware::Health::kInvalid});
  }
  const SigmaConsistency c = sigma_consistency(report);
  if (c.poses > 0) {
    const auto share = [&](std::size_t inside) {
      return format("%.1f%%", 100.0 * static_cast<double>(inside) / static_cast<double>(c.poses));
    };
    html_row(out, "x error within ±2 sigma", {share(c.inside_x)});
    html_row(out, "y error within ±2 sigma", {share(c.inside_y)});
  }
  out += "</table>\n<p class=\"note\">" +
         escape(
             "Health from the STATUSTEXTs the firmware sends on each change; sigma from each "
             "ODOMETRY's covariance. A consistent filter keeps about 95% of each axis's errors "
             "within ±2 sigma.") +
         "</p>\n";
}

// What the area log adds: each board's area and how long the filter distrusted it.
void area_table(std::string& out, const Report& report) {
  const bool distrust = report.areas->has_distrust;
  out +=
      "<h2>Boards (from the area log)</h2>\n<table class=\"areas\">\n<tr><th>board</th>"
      "<th>frames</th><th>mean area (% of frame)</th><th>min</th><th>max</th>";
  if (distrust) out += "<th>distrusted</th>";
  out += "</tr>\n";
  const double span_s = report.truth.back().t_s - report.truth.front().t_s;
  for (const BoardAreaSummary& b : board_area_summary(report)) {
    std::vector<std::string> cells = {std::to_string(b.frames), cell(b.mean_percent, 2),
                                      cell(b.min_percent, 2), cell(b.max_percent, 2)};
    if (distrust) {
      cells.push_back(format("%.1f s (%.1f%%)", b.distrusted_s,
                             span_s > 0.0 ? 100.0 * b.distrusted_s / span_s : 0.0));
    }
    html_row(out, b.name, cells);
  }
  out += "</table>\n<p class=\"note\">" +
         escape(distrust ? "Over the ground truth's time span. A board is distrusted while the "
                           "filter's motion index for it is below one half; it is then left out "
                           "of the fix."
                         : "Over the ground truth's time span. This area log has no "
                           "distrusted_mask column (an older firmware wrote it).") +
         "</p>\n";
}

}  // namespace

std::string index_html(const Report& report, const std::vector<std::string>& images) {
  std::string out;
  out +=
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>harmoloc run report</title>\n<style>";
  out += kPageCss;
  out += "</style>\n</head>\n<body>\n<h1>harmoloc run report</h1>\n";
  if (!report.inputs.title.empty()) {
    out += "<p class=\"subtitle\">" + escape(report.inputs.title) + "</p>\n";
  }

  // Accuracy table: one column per scored set.
  struct Column {
    std::string name;
    const TrajectoryErrors* errors;
    bool heading;
  };
  std::vector<Column> columns = {{"fused estimate", &report.estimate_all, true}};
  const double skip = report.inputs.skip_initial_s;
  if (report.estimate_converged) {
    columns.push_back({"fused, after " + seconds(skip), &*report.estimate_converged, true});
  }
  if (report.fixes_all) columns.push_back({"harmonic fixes", &*report.fixes_all, false});
  if (report.fixes_converged) {
    columns.push_back({"fixes, after " + seconds(skip), &*report.fixes_converged, false});
  }
  out += "<h2>Accuracy against ground truth</h2>\n<table>\n<tr><th></th>";
  for (const Column& c : columns) out += "<th>" + escape(c.name) + "</th>";
  out += "</tr>\n";
  const auto row = [&](const std::string& label, auto value, bool heading_only = false) {
    std::vector<std::string> cells;
    for (const Column& c : columns) {
      cells.push_back(heading_only && !c.heading ? "—" : value(*c.errors));
    }
    html_row(out, label, cells);
  };
  row("poses scored", [](const TrajectoryErrors& e) { return std::to_string(e.count); });
  row("RMSE x (cm)", [](const TrajectoryErrors& e) { return cell(e.rmse_x_m * 100.0, 2); });
  row("RMSE y (cm)", [](const TrajectoryErrors& e) { return cell(e.rmse_y_m * 100.0, 2); });
  row("RMSE position (cm)",
      [](const TrajectoryErrors& e) { return cell(e.rmse_position_m * 100.0, 2); });
  row("MSE x (cm²)", [](const TrajectoryErrors& e) { return cell(e.mse_x_cm2, 2); });
  row("MSE y (cm²)", [](const TrajectoryErrors& e) { return cell(e.mse_y_cm2, 2); });
  row("mean position error (cm)",
      [](const TrajectoryErrors& e) { return cell(e.mean_position_m * 100.0, 2); });
  row("p95 position error (cm)",
      [](const TrajectoryErrors& e) { return cell(e.p95_position_m * 100.0, 2); });
  row("max position error (cm)",
      [](const TrajectoryErrors& e) { return cell(e.max_position_m * 100.0, 2); });
  row(
      "RMSE heading (deg)", [](const TrajectoryErrors& e) { return cell(e.rmse_heading_deg, 2); },
      true);
  row(
      "max heading error (deg)",
      [](const TrajectoryErrors& e) { return cell(e.max_heading_deg, 2); }, true);
  out += "</table>\n";
  std::string note = "Each pose is compared with the ground truth interpolated at its time.";
  if (report.estimate_all.outside_truth > 0) {
    note += format(" %zu estimate poses outside the ground truth's time span were not scored.",
                   report.estimate_all.outside_truth);
  }
  if (skip > 0.0) {
    note += " The “after” columns leave out the first " + seconds(skip) +
            " of the ground truth (convergence).";
  }
  note += " The harmonic localizer gives no heading.";
  out += "<p class=\"note\">" + escape(note) + "</p>\n";
  relative_error_table(out, report);
  if (report.link) link_table(out, report);
  if (report.areas) area_table(out, report);

  if (report.stats) {
    const RunStats& s = *report.stats;
    out += "<h2>Run and timing</h2>\n<table>\n";
    const auto opt = [](const std::optional<std::uint64_t>& v) {
      return v ? std::to_string(*v) : std::string("n/a");
    };
    if (!s.harmoloc_version.empty()) html_row(out, "harmoloc version", {s.harmoloc_version});
    if (!s.board.empty()) html_row(out, "board", {s.board});
    html_row(out, "frames", {opt(s.frames)});
    html_row(out, "cycles", {opt(s.cycles)});
    if (s.rate_hz) html_row(out, "rate", {format("%g Hz", *s.rate_hz)});
    html_row(out, "budget per cycle", {budget(s.budget_us)});
    html_row(out, "overruns", {opt(s.overruns)}, {s.overruns && *s.overruns > 0});
    for (const auto& [name, count] : s.degraded) {
      html_row(out, "degraded: " + name + " (cycles)", {std::to_string(count)}, {count > 0});
    }
    if (s.localizer_fixes) html_row(out, "harmonic fixes", {opt(s.localizer_fixes)});
    if (s.localizer_unknown_place) {
      html_row(out, "unknown place (fix refused)", {opt(s.localizer_unknown_place)});
    }
    out += "</table>\n";

    out +=
        "<table>\n<tr><th>stage (µs)</th><th>median</th><th>p99</th><th>p99.9</th>"
        "<th>max</th><th>mean</th><th>p99 / budget</th></tr>\n";
    for (const StageTiming& st : s.stages) {
      const bool over = std::isfinite(st.max_us) && st.max_us > s.budget_us;
      html_row(out, st.name,
               {cell(st.median_us, 1), cell(st.p99_us, 1), cell(st.p999_us, 1), cell(st.max_us, 1),
                cell(st.mean_us, 1), cell(st.p99_us / s.budget_us * 100.0, 2) + " %"},
               {false, false, false, over, false, false});
    }
    out += "</table>\n<p class=\"note\">" +
           escape("Budget " + budget(s.budget_us) +
                  " per cycle; a maximum above it is shown in red.") +
           "</p>\n";
  }

  for (const std::string& image : images) {
    std::string caption;
    if (image == "trajectory.svg") {
      caption = "Ground truth and fused estimate in the map frame (metres, equal aspect).";
    } else if (image == "error.svg") {
      caption = "Position error (cm) and signed heading error (deg) over time.";
    } else if (image == "timing.svg") {
      caption =
          "Histogram of the whole-cycle compute time (true bucket widths) with its median, p99 "
          "and the budget.";
    } else if (image == "stages.svg") {
      caption = "Median and p99 compute time of each stage of the cycle.";
    } else if (image == "error_xy.svg") {
      caption = "The error's x and y components over time (estimate - truth, cm).";
    } else if (image == "sigma.svg") {
      caption = "The pose on the link: its x and y errors against the ±2 sigma it claims.";
    } else if (image == "health.svg") {
      caption = "Health over time (from the link's STATUSTEXTs) and the quality of each pose.";
    } else if (image == "areas.svg") {
      caption =
          "Each board's area (percent of the frame) over time, the periods the filter "
          "distrusted it shaded.";
    }
    out += "<figure><img src=\"" + escape(image) + "\" alt=\"" + escape(caption) +
           "\"><figcaption>" + escape(caption) + "</figcaption></figure>\n";
  }

  if (report.stats && !report.stats->sections.empty()) {
    out += "<h2>Other statistics</h2>\n<div class=\"sections\">\n";
    for (const StatsSection& section : report.stats->sections) {
      if (section.entries.empty()) continue;
      out += "<table>\n<tr><th>" + escape(section.name) + "</th><th></th></tr>\n";
      for (const auto& [key, value] : section.entries) html_row(out, key, {value});
      out += "</table>\n";
    }
    out += "</div>\n";
  }

  out += "<h2>Inputs</h2>\n<table class=\"files\">\n";
  html_row(out, "ground truth", {report.inputs.truth_path});
  html_row(out, "fused estimate", {report.inputs.estimate_path});
  if (!report.inputs.fixes_path.empty()) {
    html_row(out, "harmonic fixes", {report.inputs.fixes_path});
  }
  if (!report.inputs.stats_path.empty()) html_row(out, "stats", {report.inputs.stats_path});
  if (!report.inputs.link_path.empty()) html_row(out, "link", {report.inputs.link_path});
  if (!report.inputs.areas_path.empty()) html_row(out, "area log", {report.inputs.areas_path});
  out +=
      "</table>\n<p class=\"note\">Written by harmoloc-report. The numbers are also in "
      "<a href=\"summary.json\">summary.json</a> and <a href=\"summary.txt\">summary.txt</a>."
      "</p>\n</body>\n</html>\n";
  return out;
}

}  // namespace harmoloc::sim_host
