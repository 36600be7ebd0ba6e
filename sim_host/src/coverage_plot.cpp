#include "harmoloc/sim_host/coverage_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "harmoloc/sim_host/svg.hpp"
#include "harmoloc/sim_host/svg_plot.hpp"
#include "harmoloc/sim_host/svg_ticks.hpp"

namespace harmoloc::sim_host {

namespace {

using algorithms::ForwardMap;

constexpr const char* kPlaceColour = "#d9d9d9";
constexpr const char* kRoseColour = "#1f77b4";
constexpr double kPi = 3.14159265358979323846;

// The stored cell nearest (x, y), or kVoidCell.
std::size_t cell_at(const ForwardMap& map, double x, double y) {
  const auto cell = static_cast<double>(map.cell_m);
  const double u = std::round((x - static_cast<double>(map.origin_x_m)) / cell);
  const double v = std::round((y - static_cast<double>(map.origin_y_m)) / cell);
  if (u < 0.0 || v < 0.0 || u >= map.columns || v >= map.rows) return ForwardMap::kVoidCell;
  return map.index(static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v));
}

}  // namespace

std::string coverage_svg(const ForwardMap& map, double known_m, const std::string& title) {
  const auto cell = static_cast<double>(map.cell_m);
  const auto x0 = static_cast<double>(map.origin_x_m), y0 = static_cast<double>(map.origin_y_m);
  const double x1 = x0 + cell * (map.columns - 1.0);
  const double y1 = y0 + cell * (map.rows - 1.0);
  // One rose a block: about 30 blocks along the longer side, never finer than a cell.
  const double block = std::max(cell, std::max(x1 - x0, y1 - y0) / 30.0);
  const double plot_w = 640.0;
  const double scale = plot_w / std::max(x1 - x0, 1e-3);
  const double plot_h = std::max(120.0, (y1 - y0) * scale);
  svg::Area area{70.0, 50.0, plot_w, plot_h};
  svg::Canvas c(area.right() + 30.0, area.bottom() + 95.0);
  const svg::Scale sx{x0, x1, area.left, area.right()};
  const svg::Scale sy{y0, y0 + plot_h / scale, area.bottom(), area.top};
  const double step = svg::nice_step(std::max(x1 - x0, y1 - y0), 8);
  svg::draw_axes(c, area, svg::make_ticks(sx, step), svg::make_ticks(sy, step), "x (m)", "y (m)");
  c.text(area.left, 28.0, title, "start", 14.0);

  std::ostringstream places, roses;
  const double half = 0.5 * block * scale;
  const double radius = 0.46 * block * scale;
  std::size_t known = 0, sectors = 0;
  for (double y = y0 + 0.5 * block; y <= y1; y += block) {
    for (double x = x0 + 0.5 * block; x <= x1; x += block) {
      const std::size_t at = cell_at(map, x, y);
      if (at == ForwardMap::kVoidCell ||
          !(static_cast<double>(map.route_distance_m[at]) <= known_m))
        continue;
      const double px = sx(x), py = sy(y);
      places << "M" << svg::number(px - half) << ' ' << svg::number(py - half) << "h"
             << svg::number(2.0 * half) << "v" << svg::number(2.0 * half) << "h"
             << svg::number(-2.0 * half) << "z";
      ++known;
      if (!ForwardMap::kHeadingTermStorage || !map.has_heading_coverage) continue;
      const std::uint32_t mask = map.heading_cover[at];
      for (int k = 0; k < ForwardMap::kHeadingSectors; ++k) {
        if (((mask >> k) & 1U) == 0U) continue;
        ++sectors;
        const auto sector = static_cast<double>(ForwardMap::kHeadingSector_rad);
        const double a0 = -kPi + k * sector;
        const double a1 = a0 + sector;
        // y up in the map is y down on the page: a counter-clockwise turn is sweep 0.
        roses << "M" << svg::number(px) << ' ' << svg::number(py) << "L"
              << svg::number(px + radius * std::cos(a0)) << ' '
              << svg::number(py - radius * std::sin(a0)) << "A" << svg::number(radius) << ' '
              << svg::number(radius) << " 0 0 0 " << svg::number(px + radius * std::cos(a1)) << ' '
              << svg::number(py - radius * std::sin(a1)) << "z";
      }
    }
  }
  c.raw(svg::clip_path("coverage", area));
  c.raw("<g clip-path=\"url(#coverage)\">\n");
  if (known > 0) c.raw("<path d=\"" + places.str() + "\" fill=\"" + kPlaceColour + "\"/>\n");
  if (sectors > 0)
    c.raw("<path d=\"" + roses.str() + "\" fill=\"" + kRoseColour + "\" fill-opacity=\"0.85\"/>\n");
  c.raw("</g>\n");
  char line[200];
  std::snprintf(line, sizeof line,
                "grey: within %.0f cm of the training run; blue wedges: the headings it covers "
                "there (%.0f%% of the circle on average)",
                100.0 * known_m,
                known > 0 ? 100.0 * static_cast<double>(sectors) /
                                (static_cast<double>(known) * ForwardMap::kHeadingSectors)
                          : 0.0);
  svg::draw_caption(c, area.bottom() + 62.0,
                    {line, "a wedge points the way the camera faced (x right, y up)"});
  return c.finish();
}

}  // namespace harmoloc::sim_host
