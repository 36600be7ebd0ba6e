#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "plot_kit.hpp"

namespace harmoloc::sim_host {

std::string trajectory_svg(const Report& report) {
  // The view: the truth's box with the estimate and the fixes (trajectory_view).
  const TrajectoryView view = trajectory_view(report.truth, {&report.estimate, &report.fixes});
  const double step = view.step;
  const std::size_t outside = view.outside;

  const double max_w = 760.0, max_h = 560.0;
  const double scale = std::min(max_w / view.width(), max_h / view.height());
  const double plot_w = view.width() * scale;
  const double plot_h = view.height() * scale;
  std::vector<std::string> caption = {
      format("equal aspect, grid %g m;  %zu truth poses, %zu estimate poses", step,
             report.truth.size(), report.estimate.size())};
  if (!report.fixes.empty()) caption[0] += format(", %zu fixes", report.fixes.size());
  if (outside > 0) {
    caption.push_back(format("%zu point%s far off the route %s outside the view", outside,
                             outside == 1 ? "" : "s", outside == 1 ? "is" : "are"));
  }
  const double left_margin = 80.0, right_margin = 30.0, top = 84.0;
  const double bottom_margin = 66.0 + 15.0 * static_cast<double>(caption.size());
  const double canvas_w = std::max(640.0, plot_w + left_margin + right_margin);
  const double left = left_margin + (canvas_w - (plot_w + left_margin + right_margin)) / 2.0;
  const Area area{left, top, plot_w, plot_h};
  Canvas svg(canvas_w, top + plot_h + bottom_margin);

  const Scale sx{view.x0, view.x1, area.left, area.right()};
  const Scale sy{view.y0, view.y1, area.bottom(), area.top};  // y up

  svg.text(canvas_w / 2.0, 26.0, "Trajectory: ground truth vs fused estimate", "middle", 17.0,
           kTextColour, " font-weight=\"bold\"");
  std::vector<LegendItem> legend = {
      {LegendItem::Kind::kLine, kTruthColour, "ground truth"},
      {LegendItem::Kind::kLine, kEstimateColour, "fused estimate"},
  };
  if (!report.fixes.empty()) {
    legend.push_back({LegendItem::Kind::kDot, kFixColour, "harmonic fixes"});
  }
  legend.push_back({LegendItem::Kind::kRing, "#2ca02c", "start"});
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (canvas_w - legend_w) / 2.0, 56.0, legend);

  draw_axes(svg, area, make_ticks(sx, step), make_ticks(sy, step), "x (m)", "y (m)");

  svg.raw(clip_path("trajectory-plot", area));
  svg.raw("<g clip-path=\"url(#trajectory-plot)\">\n");
  if (!report.fixes.empty()) {
    svg.raw(format("<g class=\"fixes\" fill=\"%s\" fill-opacity=\"0.55\">\n", kFixColour));
    for (const dataset::StampedPose& p : report.fixes) {
      svg.raw(format("<circle cx=\"%s\" cy=\"%s\" r=\"1.8\"/>\n", number(sx(p.pose.x_m)).c_str(),
                     number(sy(p.pose.y_m)).c_str()));
    }
    svg.raw("</g>\n");
  }
  std::vector<std::pair<double, double>> points;
  for (const dataset::StampedPose& p : report.truth)
    points.emplace_back(sx(p.pose.x_m), sy(p.pose.y_m));
  svg.polyline(points, kTruthColour, 2.4, "truth", " stroke-opacity=\"0.85\"");
  points.clear();
  for (const dataset::StampedPose& p : report.estimate) {
    points.emplace_back(sx(p.pose.x_m), sy(p.pose.y_m));
  }
  svg.polyline(points, kEstimateColour, 1.5, "estimate");
  const dataset::StampedPose& start = report.truth.front();
  svg.circle(sx(start.pose.x_m), sy(start.pose.y_m), 6.0, "none",
             " stroke=\"#2ca02c\" stroke-width=\"2.5\"");
  svg.raw("</g>\n");

  draw_caption(svg, area.bottom() + 64.0, caption);
  return svg.finish();
}

}  // namespace harmoloc::sim_host
