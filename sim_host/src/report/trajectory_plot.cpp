#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "plot_kit.hpp"

namespace harmoloc::sim_host {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Box {
  double x0 = kInf, y0 = kInf, x1 = -kInf, y1 = -kInf;
  bool empty() const { return !(x1 >= x0); }
  void add(double x, double y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
};

}  // namespace

std::string trajectory_svg(const Report& report) {
  // The view: the truth's box, grown to take in the estimate and fixes unless they run far
  // away (then they are clipped and counted, so that one wild fix does not shrink the route).
  Box truth_box;
  for (const dataset::StampedPose& p : report.truth) truth_box.add(p.pose.x_m, p.pose.y_m);
  const double extent = std::max({truth_box.width(), truth_box.height(), 0.2});
  Box limit = truth_box;
  const double grow = 0.5 * extent + 0.5;
  limit.x0 -= grow;
  limit.y0 -= grow;
  limit.x1 += grow;
  limit.y1 += grow;
  Box view = truth_box;
  std::size_t outside = 0;
  const auto take = [&](const std::vector<dataset::StampedPose>& poses) {
    for (const dataset::StampedPose& p : poses) {
      if (limit.contains(p.pose.x_m, p.pose.y_m)) {
        view.add(p.pose.x_m, p.pose.y_m);
      } else {
        ++outside;
      }
    }
  };
  take(report.estimate);
  take(report.fixes);
  // Padding, and a minimum extent on the short side so that a straight run is not a sliver.
  double span = std::max({view.width(), view.height(), 0.2});
  const double pad = 0.04 * span;
  view.x0 -= pad;
  view.x1 += pad;
  view.y0 -= pad;
  view.y1 += pad;
  span = std::max(view.width(), view.height());
  const double min_side = 0.3 * span;
  if (view.width() < min_side) {
    const double c = 0.5 * (view.x0 + view.x1);
    view.x0 = c - 0.5 * min_side;
    view.x1 = c + 0.5 * min_side;
  }
  if (view.height() < min_side) {
    const double c = 0.5 * (view.y0 + view.y1);
    view.y0 = c - 0.5 * min_side;
    view.y1 = c + 0.5 * min_side;
  }
  const double step = nice_step(span, 8);
  view.x0 = std::floor(view.x0 / step - 1e-9) * step;
  view.y0 = std::floor(view.y0 / step - 1e-9) * step;
  view.x1 = std::ceil(view.x1 / step + 1e-9) * step;
  view.y1 = std::ceil(view.y1 / step + 1e-9) * step;

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
