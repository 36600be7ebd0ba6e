#include "harmoloc/sim_host/svg_plot.hpp"

#include <algorithm>

#include "format.hpp"

namespace harmoloc::sim_host::svg {

using report_text::format;

void draw_axes(Canvas& svg, const Area& area, const std::vector<Tick>& x_ticks,
               const std::vector<Tick>& y_ticks, const std::string& x_title,
               const std::string& y_title, bool x_grid) {
  for (const Tick& t : y_ticks) {
    svg.line(area.left, t.px, area.right(), t.px, kGridColour, 1.0);
  }
  if (x_grid) {
    for (const Tick& t : x_ticks) {
      svg.line(t.px, area.top, t.px, area.bottom(), kGridColour, 1.0);
    }
  }
  svg.rect(area.left, area.top, area.width, area.height, "none",
           format(" stroke=\"%s\" stroke-width=\"1\"", kAxisColour));
  double widest = 0.0;
  for (const Tick& t : y_ticks) {
    svg.line(area.left - 5.0, t.px, area.left, t.px, kAxisColour, 1.0);
    svg.text(area.left - 8.0, t.px + 4.0, t.label, "end", 11.0);
    widest = std::max(widest, text_width(t.label, 11.0));
  }
  for (const Tick& t : x_ticks) {
    svg.line(t.px, area.bottom(), t.px, area.bottom() + 5.0, kAxisColour, 1.0);
    svg.text(t.px, area.bottom() + 18.0, t.label, "middle", 11.0);
  }
  if (!x_title.empty()) {
    svg.text(area.left + area.width / 2.0, area.bottom() + 38.0, x_title, "middle", 12.5);
  }
  if (!y_title.empty()) {
    const double x = area.left - widest - 18.0;
    const double y = area.top + area.height / 2.0;
    svg.text(x, y, y_title, "middle", 12.5, kTextColour,
             format(" transform=\"rotate(-90 %s %s)\"", number(x).c_str(), number(y).c_str()));
  }
}

double draw_legend(Canvas& svg, double x, double y, const std::vector<LegendItem>& items,
                   bool draw) {
  double cursor = x;
  for (const LegendItem& item : items) {
    if (draw) {
      const double cy = y - 4.0;
      switch (item.kind) {
        case LegendItem::Kind::kLine:
          svg.line(cursor, cy, cursor + 22, cy, item.colour, 2.5);
          break;
        case LegendItem::Kind::kDashedLine:
          svg.line(cursor, cy, cursor + 22, cy, item.colour, 2.0, " stroke-dasharray=\"5,3\"");
          break;
        case LegendItem::Kind::kDot:
          svg.circle(cursor + 11, cy, 3.0, item.colour);
          break;
        case LegendItem::Kind::kRing:
          svg.circle(cursor + 11, cy, 5.0, "none",
                     format(" stroke=\"%s\" stroke-width=\"2\"", item.colour));
          break;
        case LegendItem::Kind::kBox:
          svg.rect(cursor + 4, cy - 6, 14, 12, item.colour);
          break;
      }
      svg.text(cursor + 28, y, item.label, "start", 12.0);
    }
    cursor += 28 + text_width(item.label, 12.0) + 20;
  }
  return cursor - x - 20;
}

std::string clip_path(const std::string& id, const Area& area) {
  return format(
      "<defs><clipPath id=\"%s\"><rect x=\"%s\" y=\"%s\" width=\"%s\" "
      "height=\"%s\"/></clipPath></defs>\n",
      escape(id).c_str(), number(area.left).c_str(), number(area.top).c_str(),
      number(area.width).c_str(), number(area.height).c_str());
}

void draw_caption(Canvas& svg, double y, const std::vector<std::string>& lines) {
  for (std::size_t i = 0; i < lines.size(); ++i) {
    svg.text(svg.width() / 2.0, y + 15.0 * static_cast<double>(i), lines[i], "middle", 11.5,
             kMutedColour);
  }
}

}  // namespace harmoloc::sim_host::svg
