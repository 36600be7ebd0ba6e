#pragma once
// One panel of a signed quantity over time (an error in cm around zero), shared by the x/y
// error plot and the 2-sigma plot so that their panels read alike: axis symmetric about zero,
// the convergence stretch shaded, data clipped to the panel.

#include <string>
#include <utility>
#include <vector>

#include "plot_kit.hpp"

namespace harmoloc::sim_host {

struct TimeSeries {
  std::vector<std::pair<double, double>> points;  ///< (time since start s, value)
  const char* colour = kEstimateColour;
  std::string css_class;
  bool dots = false;  ///< Dots (the fixes) instead of a line.
};

/// A band +-half_width(t) around zero, drawn under the data (the 2-sigma envelope).
struct TimeBand {
  std::vector<std::pair<double, double>> half_widths;  ///< (time since start s, half width)
  const char* colour = kEstimateColour;
};

struct TimePanel {
  Area area;
  double duration_s = 1.0;
  double skip_s = 0.0;  ///< Shaded from 0 to here when > 0.
  double limit = 1.0;   ///< The y axis runs -limit..limit.
  std::string title;    ///< Bold, above the panel's top-left corner.
  std::string x_title;  ///< Empty: none (a panel with another below it).
  std::string y_title;
  std::string clip_id;  ///< Unique in the document.
};

/// A round symmetric limit that holds @p largest (>= @p floor) with a little room.
double symmetric_limit(double largest, double floor);

/// The layout both two-panel figures share: x above y, under a bold title and a centred legend.
struct StackedPanels {
  double width = 860.0;
  Area top;
  Area bottom;
};
StackedPanels stacked_panels();

/// The figure's title and its legend, centred above the top panel.
void draw_figure_heading(Canvas& svg, const std::string& title,
                         const std::vector<LegendItem>& legend);

void draw_time_panel(Canvas& svg, const TimePanel& panel, const std::vector<TimeSeries>& series,
                     const TimeBand* band = nullptr);

}  // namespace harmoloc::sim_host
