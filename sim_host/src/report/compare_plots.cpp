// The comparison's two plots: each run's position error over time on one axis, and each run's
// trajectory over the ground truth in the map frame; one colour a run (run_colour()).
#include <algorithm>
#include <cmath>
#include <limits>

#include "harmoloc/sim_host/comparison.hpp"
#include "plot_kit.hpp"

namespace harmoloc::sim_host {

namespace {

std::vector<LegendItem> run_legend(const std::vector<ComparedRun>& runs, bool with_truth) {
  std::vector<LegendItem> legend;
  if (with_truth) legend.push_back({LegendItem::Kind::kLine, kTruthColour, "ground truth"});
  for (std::size_t i = 0; i < runs.size(); ++i) {
    legend.push_back(
        {LegendItem::Kind::kLine, run_colour(i),
         runs[i].name + " (RMSE " + cm(runs[i].report.estimate_all.rmse_position_m) + ")"});
  }
  return legend;
}

void centred_legend(Canvas& svg, double y, const std::vector<LegendItem>& legend) {
  const double w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, std::max(4.0, (svg.width() - w) / 2.0), y, legend);
}

}  // namespace

std::string comparison_error_svg(const std::vector<ComparedRun>& runs) {
  const Report& first = runs.front().report;
  const double t0 = first.truth.front().t_s;
  const double duration_s = std::max(first.truth.back().t_s - t0, 1e-3);
  const double skip = first.inputs.skip_initial_s;
  const double width = 860.0, left = 80.0, right = 30.0;
  const Area area{left, 84.0, width - left - right, 300.0};
  Canvas svg(width, area.bottom() + 80.0);
  svg.text(width / 2.0, 26.0, "Position error over time, run by run", "middle", 17.0, kTextColour,
           " font-weight=\"bold\"");
  std::vector<LegendItem> legend = run_legend(runs, false);
  if (skip > 0.0) legend.push_back({LegendItem::Kind::kBox, "#eeeeee", "excluded (convergence)"});
  centred_legend(svg, 56.0, legend);

  double largest_cm = 0.1;
  for (const ComparedRun& r : runs) {
    largest_cm = std::max(largest_cm, r.report.estimate_all.max_position_m * 100.0);
  }
  const double y_step = nice_step(largest_cm * 1.05, 5);
  const double y_max = std::ceil(largest_cm * 1.05 / y_step - 1e-9) * y_step;
  const Scale sx{0.0, duration_s, area.left, area.right()};
  const Scale sy{0.0, y_max, area.bottom(), area.top};
  if (skip > 0.0) {
    svg.rect(area.left, area.top, std::min(sx(skip), area.right()) - area.left, area.height,
             "#eeeeee");
  }
  draw_axes(svg, area, make_ticks(sx, nice_step(duration_s, 10)), make_ticks(sy, y_step),
            "time since start of ground truth (s)", "position error (cm)");
  svg.raw(clip_path("compare-error", area));
  svg.raw("<g clip-path=\"url(#compare-error)\">\n");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    std::vector<std::pair<double, double>> points;
    for (const ErrorSample& s : runs[i].report.estimate_all.samples) {
      points.emplace_back(sx(s.t_s - t0), sy(s.position_m * 100.0));
    }
    svg.polyline(points, run_colour(i), 1.3, format("run-error run-%zu", i),
                 " stroke-opacity=\"0.85\"");
  }
  svg.raw("</g>\n");
  draw_caption(svg, area.bottom() + 62.0,
               {format("%zu runs against the same ground truth; each pose is compared with the "
                       "truth interpolated at its time",
                       runs.size())});
  return svg.finish();
}

std::string comparison_trajectory_svg(const std::vector<ComparedRun>& runs) {
  const Report& first = runs.front().report;
  // The truth's box with every run's estimate (trajectory_view).
  std::vector<const std::vector<dataset::StampedPose>*> estimates;
  for (const ComparedRun& r : runs) estimates.push_back(&r.report.estimate);
  const TrajectoryView view = trajectory_view(first.truth, estimates);
  const double x0 = view.x0, y0 = view.y0, x1 = view.x1, y1 = view.y1, step = view.step;
  const double scale = std::min(760.0 / (x1 - x0), 560.0 / (y1 - y0));
  const double plot_w = (x1 - x0) * scale, plot_h = (y1 - y0) * scale;
  const double canvas_w = std::max(640.0, plot_w + 110.0);
  const Area area{80.0 + (canvas_w - (plot_w + 110.0)) / 2.0, 84.0, plot_w, plot_h};
  Canvas svg(canvas_w, area.bottom() + 81.0);
  const Scale sx{x0, x1, area.left, area.right()};
  const Scale sy{y0, y1, area.bottom(), area.top};

  svg.text(canvas_w / 2.0, 26.0, "Trajectories: ground truth and each run", "middle", 17.0,
           kTextColour, " font-weight=\"bold\"");
  centred_legend(svg, 56.0, run_legend(runs, true));
  draw_axes(svg, area, make_ticks(sx, step), make_ticks(sy, step), "x (m)", "y (m)");
  svg.raw(clip_path("compare-trajectory", area));
  svg.raw("<g clip-path=\"url(#compare-trajectory)\">\n");
  std::vector<std::pair<double, double>> points;
  for (const dataset::StampedPose& p : first.truth) {
    points.emplace_back(sx(p.pose.x_m), sy(p.pose.y_m));
  }
  svg.polyline(points, kTruthColour, 2.4, "truth", " stroke-opacity=\"0.85\"");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    points.clear();
    for (const dataset::StampedPose& p : runs[i].report.estimate) {
      points.emplace_back(sx(p.pose.x_m), sy(p.pose.y_m));
    }
    svg.polyline(points, run_colour(i), 1.4, format("run-trajectory run-%zu", i),
                 " stroke-opacity=\"0.85\"");
  }
  svg.raw("</g>\n");
  draw_caption(svg, area.bottom() + 64.0, {format("equal aspect, grid %g m", step)});
  return svg.finish();
}

}  // namespace harmoloc::sim_host
