// The error's x and y components over time (estimate - truth, cm): a bias along one axis, which
// the position error's length hides, shows here as a curve off zero.
#include <algorithm>
#include <cmath>

#include "harmoloc/sim_host/report.hpp"
#include "time_panel.hpp"

namespace harmoloc::sim_host {

std::string xy_error_svg(const Report& report) {
  const double t0 = report.truth.front().t_s;
  const double duration_s = std::max(report.truth.back().t_s - t0, 1e-3);
  const TrajectoryErrors& est = report.estimate_all;
  const std::optional<TrajectoryErrors>& fixes = report.fixes_all;

  // The axis holds the fused estimate and the fixes' p99, as error.svg's does: a few wild fixes
  // must not flatten the fused curve.
  double largest_cm = 0.0;
  for (const ErrorSample& s : est.samples) {
    largest_cm = std::max({largest_cm, std::fabs(s.dx_m), std::fabs(s.dy_m)});
  }
  largest_cm *= 100.0;
  if (fixes) {
    std::vector<double> e;
    for (const ErrorSample& s : fixes->samples) {
      e.push_back(std::fabs(s.dx_m) * 100.0);
      e.push_back(std::fabs(s.dy_m) * 100.0);
    }
    largest_cm = std::max(largest_cm, percentile(e, 99.0));
  }
  const double limit_cm = symmetric_limit(largest_cm, 0.5);

  const auto [width, top, bottom] = stacked_panels();
  Canvas svg(width, bottom.bottom() + 80.0);
  std::vector<LegendItem> legend = {{LegendItem::Kind::kLine, kEstimateColour, "fused estimate"}};
  if (fixes) legend.push_back({LegendItem::Kind::kDot, kFixColour, "harmonic fixes"});
  if (report.inputs.skip_initial_s > 0.0) {
    legend.push_back({LegendItem::Kind::kBox, "#eeeeee", "excluded (convergence)"});
  }
  draw_figure_heading(svg, "Error components over time (estimate - truth)", legend);

  for (const bool x_axis : {true, false}) {
    TimePanel panel;
    panel.area = x_axis ? top : bottom;
    panel.duration_s = duration_s;
    panel.skip_s = report.inputs.skip_initial_s;
    panel.limit = limit_cm;
    panel.title = format("%s error, RMSE %s", x_axis ? "x" : "y",
                         cm(x_axis ? est.rmse_x_m : est.rmse_y_m).c_str());
    panel.y_title = x_axis ? "x error (cm)" : "y error (cm)";
    panel.x_title = x_axis ? "" : "time since start of ground truth (s)";
    panel.clip_id = x_axis ? "xy-error-x" : "xy-error-y";
    std::vector<TimeSeries> series;
    if (fixes) {
      TimeSeries f;
      f.colour = kFixColour;
      f.css_class = x_axis ? "fixes-x" : "fixes-y";
      f.dots = true;
      for (const ErrorSample& s : fixes->samples) {
        f.points.emplace_back(s.t_s - t0, (x_axis ? s.dx_m : s.dy_m) * 100.0);
      }
      series.push_back(std::move(f));
    }
    TimeSeries e;
    e.css_class = x_axis ? "x-error" : "y-error";
    for (const ErrorSample& s : est.samples) {
      e.points.emplace_back(s.t_s - t0, (x_axis ? s.dx_m : s.dy_m) * 100.0);
    }
    series.push_back(std::move(e));
    draw_time_panel(svg, panel, series);
  }
  double mean_x = 0.0, mean_y = 0.0;
  for (const ErrorSample& s : est.samples) {
    mean_x += s.dx_m;
    mean_y += s.dy_m;
  }
  const double n = static_cast<double>(std::max<std::size_t>(est.samples.size(), 1));
  draw_caption(svg, bottom.bottom() + 62.0,
               {format("fused estimate: mean x error %s, mean y error %s (a bias shows as a mean "
                       "away from 0)",
                       cm(mean_x / n).c_str(), cm(mean_y / n).c_str())});
  return svg.finish();
}

}  // namespace harmoloc::sim_host
