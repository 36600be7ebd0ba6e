// Each board's area over time (percent of the frame, from the area log), one small panel a
// board in the log's column order, with the periods the filter distrusted the board shaded: a
// board that is moved, covered or out of view shows as an area that changes while shaded.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "harmoloc/sim_host/report.hpp"
#include "plot_kit.hpp"

namespace harmoloc::sim_host {

namespace {

constexpr const char* kDistrustColour = "#f4c7c3";

/// A readable stroke for a board named after its colour (yellow and cyan darkened for a white
/// background); other names take a colour by position.
const char* board_colour(const std::string& name, std::size_t index) {
  static constexpr std::pair<const char*, const char*> kNamed[] = {
      {"red", "#d62728"},     {"green", "#2ca02c"}, {"blue", "#1f77b4"},   {"yellow", "#b8a000"},
      {"magenta", "#c21fc2"}, {"cyan", "#12a4b5"},  {"orange", "#ff7f0e"}, {"purple", "#9467bd"},
      {"pink", "#e377c2"},    {"brown", "#8c564b"}, {"black", "#222222"},  {"white", "#999999"}};
  for (const auto& [n, c] : kNamed) {
    if (name == n) return c;
  }
  static constexpr const char* kByIndex[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                             "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
  return kByIndex[index % (sizeof kByIndex / sizeof kByIndex[0])];
}

}  // namespace

std::string areas_svg(const Report& report) {
  const dataset::AreaLog& log = *report.areas;
  const double t0 = report.truth.front().t_s;
  const double duration_s = std::max(report.truth.back().t_s - t0, 1e-3);
  const double frame_px =
      static_cast<double>(log.image_width_px) * static_cast<double>(log.image_height_px);
  const std::size_t boards = log.board_names.size();
  const std::vector<BoardAreaSummary> summary = board_area_summary(report);

  const double width = 860.0, left = 80.0, right = 30.0, panel_h = 62.0, gap = 50.0;
  const double first_top = 92.0;
  const double last_bottom = first_top + static_cast<double>(boards) * (panel_h + gap) - gap;
  std::vector<std::string> caption;
  Canvas svg(width, last_bottom + 70.0 + 15.0 * 2.0);
  svg.text(width / 2.0, 26.0, "Board areas over time (from the area log)", "middle", 17.0,
           kTextColour, " font-weight=\"bold\"");
  std::vector<LegendItem> legend;
  for (std::size_t b = 0; b < boards; ++b) {
    legend.push_back(
        {LegendItem::Kind::kLine, board_colour(log.board_names[b], b), log.board_names[b]});
  }
  if (log.has_distrust) {
    legend.push_back({LegendItem::Kind::kBox, kDistrustColour, "distrusted by the filter"});
  }
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, std::max(0.0, (width - legend_w) / 2.0), 56.0, legend);

  const Scale sx{0.0, duration_s, left, width - right};
  const double x_step = nice_step(duration_s, 10);
  for (std::size_t b = 0; b < boards; ++b) {
    const Area area{left, first_top + static_cast<double>(b) * (panel_h + gap),
                    width - left - right, panel_h};
    const char* colour = board_colour(log.board_names[b], b);
    double largest = 0.0;
    std::vector<std::pair<double, double>> points;
    points.reserve(log.areas.size());
    for (std::size_t i = 0; i < log.areas.size(); ++i) {
      const double percent = 100.0 * static_cast<double>(log.areas[i].pixels[b]) / frame_px;
      largest = std::max(largest, percent);
      points.emplace_back(static_cast<double>(log.timestamp_ns[i]) * 1e-9 - t0, percent);
    }
    const double y_step = nice_step(std::max(largest, 0.1) * 1.1, 3);
    const double y_max = std::ceil(std::max(largest, 0.1) * 1.1 / y_step - 1e-9) * y_step;
    const Scale sy{0.0, y_max, area.bottom(), area.top};
    const std::vector<TimeSpan> spans = distrusted_spans(log, b);

    const std::string clip = format("areas-%zu", b);
    svg.raw(clip_path(clip, area));
    svg.raw(format("<g class=\"distrusted\" data-board=\"%s\" clip-path=\"url(#%s)\">\n",
                   svg::escape(log.board_names[b]).c_str(), clip.c_str()));
    for (const TimeSpan& s : spans) {
      const double xa = sx(s.start_s - t0), xb = sx(s.end_s - t0);
      svg.rect(xa, area.top, std::max(xb - xa, 1.0), area.height, kDistrustColour);
    }
    svg.raw("</g>\n");
    draw_axes(svg, area, make_ticks(sx, x_step), make_ticks(sy, y_step),
              b + 1 == boards ? "time since start of ground truth (s)" : "", "% of frame");
    const BoardAreaSummary& sum = summary[b];
    std::string title = format("%s: mean %.2f%% of the frame", sum.name.c_str(), sum.mean_percent);
    if (log.has_distrust) {
      title += format(", distrusted %.1f s (%.1f%%)", sum.distrusted_s,
                      100.0 * sum.distrusted_s / duration_s);
    }
    svg.text(area.left + 6.0, area.top - 8.0, title, "start", 13.0, kTextColour,
             " font-weight=\"bold\"");
    std::vector<std::pair<double, double>> px;
    px.reserve(points.size());
    for (const auto& [t, v] : points) px.emplace_back(sx(t), sy(v));
    svg.raw(format("<g clip-path=\"url(#%s)\">\n", clip.c_str()));
    svg.polyline(px, colour, 1.3, "area");
    svg.raw("</g>\n");
  }
  caption.push_back(
      format("%zu frames of %ux%u px; the area is each board's pixel count as the "
             "firmware's segmentation measured it",
             log.areas.size(), log.image_width_px, log.image_height_px));
  caption.push_back(log.has_distrust
                        ? "shaded: the filter distrusted the board (motion index below 1/2) and "
                          "left it out of the fix"
                        : "this area log has no distrusted_mask column (written by an older "
                          "firmware): no distrust shown");
  draw_caption(svg, last_bottom + 70.0, caption);
  return svg.finish();
}

}  // namespace harmoloc::sim_host
