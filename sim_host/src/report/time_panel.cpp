#include "time_panel.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::sim_host {

double symmetric_limit(double largest, double floor) {
  const double v = std::max(largest, floor);
  const double step = nice_step(2.0 * v * 1.05, 4);
  return std::ceil(v * 1.05 / step - 1e-9) * step;
}

StackedPanels stacked_panels() {
  StackedPanels p;
  const double left = 80.0, right = 30.0;
  p.top = Area{left, 84.0, p.width - left - right, 200.0};
  p.bottom = Area{left, p.top.bottom() + 50.0, p.width - left - right, 200.0};
  return p;
}

void draw_figure_heading(Canvas& svg, const std::string& title,
                         const std::vector<LegendItem>& legend) {
  svg.text(svg.width() / 2.0, 26.0, title, "middle", 17.0, kTextColour, " font-weight=\"bold\"");
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (svg.width() - legend_w) / 2.0, 56.0, legend);
}

void draw_time_panel(Canvas& svg, const TimePanel& panel, const std::vector<TimeSeries>& series,
                     const TimeBand* band) {
  const Area& a = panel.area;
  const Scale sx{0.0, panel.duration_s, a.left, a.right()};
  const Scale sy{-panel.limit, panel.limit, a.bottom(), a.top};
  if (panel.skip_s > 0.0) {
    svg.rect(a.left, a.top, std::min(sx(panel.skip_s), a.right()) - a.left, a.height, "#eeeeee");
  }
  draw_axes(svg, a, make_ticks(sx, nice_step(panel.duration_s, 10)),
            make_ticks(sy, nice_step(2.0 * panel.limit, 4)), panel.x_title, panel.y_title);
  if (!panel.title.empty()) {
    svg.text(a.left + 6.0, a.top - 8.0, panel.title, "start", 13.0, kTextColour,
             " font-weight=\"bold\"");
  }
  svg.line(a.left, sy(0.0), a.right(), sy(0.0), kAxisColour, 1.0);
  svg.raw(clip_path(panel.clip_id, a));
  svg.raw("<g clip-path=\"url(#" + panel.clip_id + ")\">\n");
  if (band != nullptr && !band->half_widths.empty()) {
    // One closed outline: the upper edge left to right, the lower edge back.
    std::string d;
    for (const auto& [t, w] : band->half_widths) {
      d += (d.empty() ? "M" : " L") + number(sx(t)) + "," +
           number(sy(std::min(w, 2.0 * panel.limit)));
    }
    for (auto it = band->half_widths.rbegin(); it != band->half_widths.rend(); ++it) {
      d +=
          " L" + number(sx(it->first)) + "," + number(sy(-std::min(it->second, 2.0 * panel.limit)));
    }
    svg.raw(
        format("<path class=\"band\" d=\"%s Z\" fill=\"%s\" fill-opacity=\"0.18\" stroke=\"%s\" "
               "stroke-opacity=\"0.5\" stroke-width=\"0.8\"/>\n",
               d.c_str(), band->colour, band->colour));
  }
  for (const TimeSeries& s : series) {
    if (s.dots) {
      svg.raw(format("<g class=\"%s\" fill=\"%s\" fill-opacity=\"0.5\">\n", s.css_class.c_str(),
                     s.colour));
      for (const auto& [t, v] : s.points) {
        svg.raw("<circle cx=\"" + number(sx(t)) + "\" cy=\"" + number(sy(v)) + "\" r=\"1.4\"/>\n");
      }
      svg.raw("</g>\n");
      continue;
    }
    std::vector<std::pair<double, double>> px;
    px.reserve(s.points.size());
    for (const auto& [t, v] : s.points) px.emplace_back(sx(t), sy(v));
    svg.polyline(px, s.colour, 1.3, s.css_class);
  }
  svg.raw("</g>\n");
}

}  // namespace harmoloc::sim_host
