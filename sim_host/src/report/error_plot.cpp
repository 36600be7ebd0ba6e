#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "plot_kit.hpp"

namespace harmoloc::sim_host {

namespace {
constexpr double kRadToDeg = 180.0 / algorithms::kPi;
}  // namespace

std::string error_svg(const Report& report) {
  const double t0 = report.truth.front().t_s;
  const double duration_s = std::max(report.truth.back().t_s - t0, 1e-3);
  const TrajectoryErrors& est = report.estimate_all;
  const std::optional<TrajectoryErrors>& fixes = report.fixes_all;

  const double width = 860.0;
  const double left = 80.0, right = 30.0;
  const Area top_area{left, 84.0, width - left - right, 250.0};
  const Area bottom_area{left, top_area.bottom() + 56.0, width - left - right, 170.0};
  const double skip = report.inputs.skip_initial_s;
  std::vector<std::string> caption = {format("fused estimate: %zu poses, RMSE %s, max %s",
                                             est.count, cm(est.rmse_position_m).c_str(),
                                             cm(est.max_position_m).c_str())};
  if (est.outside_truth > 0) {
    caption[0] +=
        format(";  %zu poses outside the ground truth's time span not scored", est.outside_truth);
  }
  if (skip > 0.0) {
    caption.push_back(
        format("the first %g s (shaded) are left out of the \"after\" numbers", skip));
  }
  if (fixes) caption.push_back("");  // filled in once the panel's range is known
  Canvas svg(width, bottom_area.bottom() + 62.0 + 15.0 * static_cast<double>(caption.size()));

  svg.text(width / 2.0, 26.0, "Error against ground truth over time", "middle", 17.0, kTextColour,
           " font-weight=\"bold\"");
  std::vector<LegendItem> legend = {
      {LegendItem::Kind::kLine, kEstimateColour, "fused estimate"},
      {LegendItem::Kind::kDashedLine, kEstimateColour, "fused RMSE " + cm(est.rmse_position_m)}};
  if (fixes) legend.push_back({LegendItem::Kind::kDot, kFixColour, "harmonic fixes"});
  if (report.inputs.skip_initial_s > 0.0) {
    legend.push_back({LegendItem::Kind::kBox, "#eeeeee", "excluded (convergence)"});
  }
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (width - legend_w) / 2.0, 56.0, legend);

  const double x_step = nice_step(duration_s, 10);
  const Scale sx_top{0.0, duration_s, top_area.left, top_area.right()};
  const Scale sx_bottom{0.0, duration_s, bottom_area.left, bottom_area.right()};

  // Position panel. A few wild fixes must not flatten the fused curve: the panel reaches the
  // fixes' p99 and clips the rest (counted in the caption).
  double y_max_cm = est.max_position_m * 100.0;
  std::size_t fixes_above = 0;
  if (fixes) {
    std::vector<double> e;
    for (const ErrorSample& s : fixes->samples) e.push_back(s.position_m * 100.0);
    y_max_cm = std::max(y_max_cm, percentile(e, 99.0));
  }
  y_max_cm = std::max(y_max_cm, 0.1);
  const double y_step = nice_step(y_max_cm * 1.05, 5);
  y_max_cm = std::ceil(y_max_cm * 1.05 / y_step - 1e-9) * y_step;
  const Scale sy_top{0.0, y_max_cm, top_area.bottom(), top_area.top};
  if (fixes) {
    for (const ErrorSample& s : fixes->samples) fixes_above += s.position_m * 100.0 > y_max_cm;
  }

  const auto shade_skip = [&](const Area& area, const Scale& sx) {
    if (skip <= 0.0) return;
    svg.rect(area.left, area.top, std::min(sx(skip), area.right()) - area.left, area.height,
             "#eeeeee");
  };
  shade_skip(top_area, sx_top);
  draw_axes(svg, top_area, make_ticks(sx_top, x_step), make_ticks(sy_top, y_step), "",
            "position error (cm)");
  svg.text(top_area.left + 6.0, top_area.top - 8.0, "position error", "start", 13.0, kTextColour,
           " font-weight=\"bold\"");

  svg.raw(clip_path("error-top", top_area));
  svg.raw("<g clip-path=\"url(#error-top)\">\n");
  if (fixes) {
    svg.raw(format("<g class=\"fixes\" fill=\"%s\" fill-opacity=\"0.5\">\n", kFixColour));
    for (const ErrorSample& s : fixes->samples) {
      svg.raw(format("<circle cx=\"%s\" cy=\"%s\" r=\"1.4\"/>\n",
                     number(sx_top(s.t_s - t0)).c_str(),
                     number(sy_top(s.position_m * 100.0)).c_str()));
    }
    svg.raw("</g>\n");
  }
  std::vector<std::pair<double, double>> points;
  for (const ErrorSample& s : est.samples) {
    points.emplace_back(sx_top(s.t_s - t0), sy_top(s.position_m * 100.0));
  }
  svg.polyline(points, kEstimateColour, 1.4, "position-error");
  const double rmse_y = sy_top(est.rmse_position_m * 100.0);
  svg.line(top_area.left, rmse_y, top_area.right(), rmse_y, kEstimateColour, 1.2,
           " stroke-dasharray=\"6,4\"");
  svg.raw("</g>\n");

  // Heading panel: signed error, symmetric axis.
  const double h_max = std::max(est.max_heading_deg, 0.5);
  const double h_step = nice_step(2.0 * h_max * 1.05, 4);
  const double h_lim = std::ceil(h_max * 1.05 / h_step - 1e-9) * h_step;
  const Scale sy_bottom{-h_lim, h_lim, bottom_area.bottom(), bottom_area.top};
  shade_skip(bottom_area, sx_bottom);
  draw_axes(svg, bottom_area, make_ticks(sx_bottom, x_step), make_ticks(sy_bottom, h_step),
            "time since start of ground truth (s)", "heading error (deg)");
  svg.text(bottom_area.left + 6.0, bottom_area.top - 8.0,
           format("heading error (estimate - truth), RMSE %.2f deg", est.rmse_heading_deg), "start",
           13.0, kTextColour, " font-weight=\"bold\"");
  svg.line(bottom_area.left, sy_bottom(0.0), bottom_area.right(), sy_bottom(0.0), kAxisColour, 1.0);
  points.clear();
  for (const ErrorSample& s : est.samples) {
    points.emplace_back(sx_bottom(s.t_s - t0), sy_bottom(s.heading_rad * kRadToDeg));
  }
  svg.raw(clip_path("error-bottom", bottom_area));
  svg.raw("<g clip-path=\"url(#error-bottom)\">\n");
  svg.polyline(points, kEstimateColour, 1.4, "heading-error");
  svg.raw("</g>\n");

  if (fixes) {
    caption.back() =
        format("harmonic fixes: %zu, RMSE %s", fixes->count, cm(fixes->rmse_position_m).c_str());
    if (fixes_above > 0) {
      caption.back() +=
          format(";  %zu above the panel (max %s)", fixes_above, cm(fixes->max_position_m).c_str());
    }
  }
  draw_caption(svg, bottom_area.bottom() + 62.0, caption);
  return svg.finish();
}

}  // namespace harmoloc::sim_host
