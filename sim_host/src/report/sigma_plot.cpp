// The spread the firmware claims (2 sigma, from ODOMETRY's covariance on the link) against the
// error it actually makes, per axis: a filter that is honest about itself keeps about 95% of its
// errors inside the band; far fewer means it is overconfident, which an autopilot fusing the pose
// would pay for.
#include <algorithm>
#include <cmath>

#include "harmoloc/sim_host/report.hpp"
#include "time_panel.hpp"

namespace harmoloc::sim_host {

SigmaConsistency sigma_consistency(const Report& report) {
  SigmaConsistency c;
  if (!report.link) return c;
  for (const LinkPose& p : report.link->poses) {
    algorithms::Pose2 truth;
    if (!dataset::interpolate(report.truth, p.t_s, truth)) continue;
    ++c.poses;
    const double bound_m = 2.0 * p.sigma_m;
    c.inside_x += std::fabs(p.pose.x_m - truth.x_m) <= bound_m;
    c.inside_y += std::fabs(p.pose.y_m - truth.y_m) <= bound_m;
  }
  return c;
}

std::string sigma_svg(const Report& report) {
  const double t0 = report.truth.front().t_s;
  const double duration_s = std::max(report.truth.back().t_s - t0, 1e-3);
  TimeSeries ex, ey;
  ex.css_class = "x-error";
  ey.css_class = "y-error";
  TimeBand band;
  double largest_cm = 0.0;
  if (report.link) {
    for (const LinkPose& p : report.link->poses) {
      algorithms::Pose2 truth;
      if (!dataset::interpolate(report.truth, p.t_s, truth)) continue;
      const double dx_cm = (p.pose.x_m - truth.x_m) * 100.0;
      const double dy_cm = (p.pose.y_m - truth.y_m) * 100.0;
      ex.points.emplace_back(p.t_s - t0, dx_cm);
      ey.points.emplace_back(p.t_s - t0, dy_cm);
      band.half_widths.emplace_back(p.t_s - t0, 2.0 * p.sigma_m * 100.0);
      largest_cm = std::max({largest_cm, std::fabs(dx_cm), std::fabs(dy_cm)});
    }
  }
  // The band may run far off while the pose is unobserved; the axis follows the errors (and the
  // band's median), the rest of the band is clipped.
  std::vector<double> widths;
  for (const auto& [t, w] : band.half_widths) widths.push_back(w);
  const double limit_cm = symmetric_limit(std::max(largest_cm, percentile(widths, 50.0)), 0.5);

  const auto [width, top, bottom] = stacked_panels();
  Canvas svg(width, bottom.bottom() + 95.0);
  draw_figure_heading(svg, "Claimed spread (2 sigma) against the actual error",
                      {{LegendItem::Kind::kLine, kEstimateColour, "error of the pose on the link"},
                       {LegendItem::Kind::kBox, "#c7dcef", "± 2 sigma (ODOMETRY covariance)"}});

  const SigmaConsistency c = sigma_consistency(report);
  const auto share = [&](std::size_t inside) {
    return c.poses == 0 ? std::string("n/a")
                        : format("%.1f%%", 100.0 * static_cast<double>(inside) /
                                               static_cast<double>(c.poses));
  };
  for (const bool x_axis : {true, false}) {
    TimePanel panel;
    panel.area = x_axis ? top : bottom;
    panel.duration_s = duration_s;
    panel.limit = limit_cm;
    panel.title = format("%s error: %s of poses within ±2 sigma", x_axis ? "x" : "y",
                         share(x_axis ? c.inside_x : c.inside_y).c_str());
    panel.y_title = x_axis ? "x error (cm)" : "y error (cm)";
    panel.x_title = x_axis ? "" : "time since start of ground truth (s)";
    panel.clip_id = x_axis ? "sigma-x" : "sigma-y";
    band.colour = kEstimateColour;
    draw_time_panel(svg, panel, {x_axis ? ex : ey}, &band);
  }
  draw_caption(svg, bottom.bottom() + 62.0,
               {format("%zu poses from the link file; sigma is the per-axis spread the firmware "
                       "sends (sqrt of the mean of the x and y variances)",
                       c.poses),
                "a consistent filter keeps about 95% of each axis's errors inside ±2 sigma"});
  return svg.finish();
}

}  // namespace harmoloc::sim_host
