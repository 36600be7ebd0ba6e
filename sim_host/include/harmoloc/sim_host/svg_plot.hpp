#pragma once
/// @file The furniture of a plot on an svg::Canvas: its area, axes with grid and titles, a
/// legend row, a clip path and a caption.

#include <string>
#include <vector>

#include "harmoloc/sim_host/svg.hpp"
#include "harmoloc/sim_host/svg_ticks.hpp"

namespace harmoloc::sim_host::svg {

/// The plotting rectangle, in pixels.
struct Area {
  double left = 0.0;
  double top = 0.0;
  double width = 0.0;
  double height = 0.0;
  double right() const { return left + width; }
  double bottom() const { return top + height; }
};

/// Grid, frame, ticks, tick labels and axis titles of one plot area. The y title sits clear of
/// the widest y tick label. Empty titles are left out.
void draw_axes(Canvas& svg, const Area& area, const std::vector<Tick>& x_ticks,
               const std::vector<Tick>& y_ticks, const std::string& x_title,
               const std::string& y_title, bool x_grid = true);

struct LegendItem {
  enum class Kind { kLine, kDashedLine, kDot, kRing, kBox };
  Kind kind;
  const char* colour;
  std::string label;
};

/// One row of legend entries starting at (x, y) (y = text baseline). Returns the row's width;
/// with @p draw false it only measures, so that a caller can centre the row.
double draw_legend(Canvas& svg, double x, double y, const std::vector<LegendItem>& items,
                   bool draw = true);

/// A <defs> block with a clip path named @p id around @p area, for data that may run outside.
std::string clip_path(const std::string& id, const Area& area);

/// Centred caption lines under a plot, 15 px apart, first baseline at @p y.
void draw_caption(Canvas& svg, double y, const std::vector<std::string>& lines);

}  // namespace harmoloc::sim_host::svg
