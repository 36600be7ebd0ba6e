#pragma once
/// @file What the report's four plots share: the SVG toolkit, the text formats, and one palette
/// (one colour for each thing plotted, so that the fused estimate is blue and the harmonic fixes
/// orange in every plot). Private to the plot files, hence the using-declarations.

#include <cstddef>
#include <vector>

#include "format.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/sim_host/svg.hpp"
#include "harmoloc/sim_host/svg_plot.hpp"
#include "harmoloc/sim_host/svg_ticks.hpp"

namespace harmoloc::sim_host {

inline constexpr const char* kTruthColour = "#222222";
inline constexpr const char* kEstimateColour = "#1f77b4";
inline constexpr const char* kFixColour = "#ff7f0e";
inline constexpr const char* kMedianColour = "#2ca02c";
inline constexpr const char* kP99Colour = "#d62728";

using report_text::budget;
using report_text::cm;
using report_text::duration;
using report_text::format;
using svg::Area;
using svg::Canvas;
using svg::clip_path;
using svg::draw_axes;
using svg::draw_caption;
using svg::draw_legend;
using svg::kAxisColour;
using svg::kMutedColour;
using svg::kTextColour;
using svg::LegendItem;
using svg::make_ticks;
using svg::nice_step;
using svg::number;
using svg::Scale;
using svg::text_width;
using svg::Tick;
using svg::ticks_in;

/// The view of a trajectory plot in the map frame (trajectory_view.cpp): the truth's box, grown
/// to take in @p others unless they run far away, padded, at least 0.3 of the long side on the
/// short one, and on a grid of @p step; @p outside counts the poses left out.
struct TrajectoryView {
  double x0, y0, x1, y1;
  double step;
  std::size_t outside;
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
};
TrajectoryView trajectory_view(const std::vector<dataset::StampedPose>& truth,
                               const std::vector<const std::vector<dataset::StampedPose>*>& others);

}  // namespace harmoloc::sim_host
