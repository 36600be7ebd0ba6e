#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>

#include "plot_kit.hpp"

namespace harmoloc::sim_host {

std::string stages_svg(const RunStats& stats) {
  const double width = 860.0;
  const double row_h = 34.0;
  double label_w = 0.0;
  for (const StageTiming& s : stats.stages) label_w = std::max(label_w, text_width(s.name, 13.0));
  const double value_w = 230.0;  // room for the value text right of the bars
  const Area area{label_w + 34.0, 84.0, width - label_w - 34.0 - value_w,
                  row_h * static_cast<double>(std::max<std::size_t>(stats.stages.size(), 1))};
  Canvas svg(width, area.bottom() + 80.0);
  svg.text(width / 2.0, 26.0, "Per-stage compute time (median and p99)", "middle", 17.0,
           kTextColour, " font-weight=\"bold\"");
  const std::vector<LegendItem> legend = {
      {LegendItem::Kind::kBox, "#9ecae1", "median"},
      {LegendItem::Kind::kBox, "#2171b5", "p99"},
  };
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (width - legend_w) / 2.0, 56.0, legend);

  double top_us = 0.0;
  for (const StageTiming& s : stats.stages) {
    if (std::isfinite(s.p99_us)) top_us = std::max(top_us, s.p99_us);
    if (std::isfinite(s.median_us)) top_us = std::max(top_us, s.median_us);
  }
  top_us = std::max(top_us, 1.0);
  const bool in_ms = top_us >= 2000.0;
  const double divisor = in_ms ? 1000.0 : 1.0;
  const double step = nice_step(top_us * 1.02, 6);
  top_us = std::ceil(top_us * 1.02 / step - 1e-9) * step;
  const Scale sx{0.0, top_us, area.left, area.right()};
  draw_axes(svg, area, make_ticks(sx, step, divisor), {},
            in_ms ? "compute time (ms)" : "compute time (µs)", "");

  svg.text(area.right() + 8.0, area.top - 8.0, "median / p99  (max)", "start", 11.5, kMutedColour);
  for (std::size_t i = 0; i < stats.stages.size(); ++i) {
    const StageTiming& s = stats.stages[i];
    const double y = area.top + row_h * static_cast<double>(i);
    if (s.name == "cycle" && i > 0) {
      svg.line(area.left - label_w - 20.0, y, area.right() + value_w - 10.0, y, "#999999", 1.0);
    }
    svg.text(area.left - 10.0, y + row_h / 2.0 + 4.5, s.name, "end", 13.0, kTextColour,
             s.name == "cycle" ? " font-weight=\"bold\"" : "");
    const auto bar = [&](double us, double offset, const char* colour) {
      if (!std::isfinite(us)) return;
      svg.rect(area.left, y + offset, std::max(1.0, sx(std::min(us, top_us)) - area.left), 11.0,
               colour);
    };
    bar(s.median_us, 5.0, "#9ecae1");
    bar(s.p99_us, 17.0, "#2171b5");
    svg.text(area.right() + 8.0, y + row_h / 2.0 + 4.5,
             format("%s / %s  (max %s)", duration(s.median_us, true).c_str(),
                    duration(s.p99_us, true).c_str(), duration(s.max_us, true).c_str()),
             "start", 11.5);
  }
  std::string caption =
      format("cycle budget %s (far right of this scale)", budget(stats.budget_us).c_str());
  if (const StageTiming* cycle = stats.stage("cycle")) {
    if (std::isfinite(cycle->p99_us)) {
      caption = format("cycle budget %s: the cycle's p99 uses %.1f%% of it",
                       budget(stats.budget_us).c_str(), cycle->p99_us / stats.budget_us * 100.0);
    }
  }
  svg.text(width / 2.0, area.bottom() + 62.0, caption, "middle", 11.5, kMutedColour);
  return svg.finish();
}

}  // namespace harmoloc::sim_host
