#pragma once
/// @file A small SVG line chart for the host tools' reports: one x axis, one or more series, an
/// optional dashed reference line (a target or a bound). Its ticks and escaping are the SVG
/// toolkit's (svg_ticks.hpp, svg.hpp); its own compact markup is kept so that charts already
/// published (docs/images) do not change.

#include <string>
#include <vector>

namespace harmoloc::sim_host {

struct Series {
  std::string name, colour;
  std::vector<double> y;
};

/// A stretch of the x axis to shade (an event: an occlusion, a moved board).
struct Span {
  double from, to;
  std::string label;
};

/// The chart as a standalone SVG document. @p reference > 0 draws a dashed line at that value
/// labelled @p reference_label; @p markers puts a dot on every point (for short series);
/// @p spans are shaded behind the lines.
std::string line_chart(const std::string& title, const std::string& x_label,
                       const std::string& y_label, const std::vector<double>& x,
                       const std::vector<Series>& series, double reference = -1.0,
                       const std::string& reference_label = "", bool markers = true,
                       const std::vector<Span>& spans = {});

}  // namespace harmoloc::sim_host
